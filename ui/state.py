"""The URL carries the design and the page state: ?r2=0.085&material=tungsten&config=nes&V=30.

Design keys are the parameter names (only those that differ from the material's values are
written); everything else is page state, kept as it is when the design changes.
"""

from __future__ import annotations

from typing import Any

from shimmy.errors import InvalidParameterError
from shimmy.model.parameters import MATERIALS, PARAMETER_SPECS, Parameters

DEFAULT_MATERIAL = "steel"


def material_params(material: str) -> dict[str, float]:
    return Parameters().with_material(material).to_dict()


def design_from_query(query: dict[str, str]) -> tuple[str, dict[str, float], list[str]]:
    """(material, complete parameter values, problems) from URL keys; bad keys are reported, not applied."""
    problems = []
    material = query.get("material", DEFAULT_MATERIAL)
    if material not in MATERIALS:
        problems.append(f"material={material!r} is not one of {', '.join(MATERIALS)}; using {DEFAULT_MATERIAL}")
        material = DEFAULT_MATERIAL
    values = material_params(material)
    for name, raw in query.items():
        if name not in PARAMETER_SPECS:
            continue
        try:
            Parameters().with_overrides({name: raw})
            values[name] = float(raw)
        except InvalidParameterError as exc:
            problems.append(str(exc))
    return material, values, problems


def design_query(material: str, values: dict[str, float]) -> dict[str, Any]:
    """The URL keys of a design: the material (if not the default) and the values that differ from it."""
    base = material_params(material)
    out: dict[str, Any] = {"material": None if material == DEFAULT_MATERIAL else material}
    for name, value in values.items():
        if _differs(name, value, base):
            out[name] = f"{float(value):.10g}"
    return out


def design_request(material: str, values: dict[str, float]) -> dict[str, Any]:
    """The {"material", "params"} part of a service request for this design."""
    base = material_params(material)
    # the values themselves (not the address's 10 digits): a design reopened from its link or its file
    # asks for exactly what it asked before, and the shared cache answers
    params = {name: float(value) for name, value in values.items() if _differs(name, value, base)}
    return {"material": material, "params": params}


def _differs(name: str, value: Any, base: dict[str, float]) -> bool:
    return value is not None and name in base and abs(float(value) - base[name]) > 1e-12 * max(1.0, abs(base[name]))
