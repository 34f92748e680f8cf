"""Directives that write the docs' reference tables from the code, so that no table is copied by hand.

* ``shimmy-parameters`` (option ``:group: gear|nes|pd``): every parameter of
  :data:`shimmy.model.parameters.PARAMETER_SPECS` with unit, default, range and provenance.
* ``shimmy-operating-points``: the nine operating points of :mod:`shimmy.model.configurations`.
* ``shimmy-calibration-targets``: the published results the calibration fits
  (:mod:`shimmy.analyses.core.calibration`).
* ``shimmy-endpoints``: method, path, summary and status codes of every path of the OpenAPI document
  (:func:`shimmy.service.api.openapi_document`).
* ``shimmy-request NAME``: the fields of one request schema (:data:`shimmy.service.schemas.SCHEMAS`).
* ``shimmy-job-statuses``: the job states and analyses of the OpenAPI ``Job`` schema.
* ``shimmy-limits``: the service's limits and environment variables (:mod:`shimmy.service.settings`).
* ``shimmy-openapi``: the whole OpenAPI document as JSON.
* ``shimmy-cli``: every subcommand of :func:`shimmy.cli.build_parser` with its options.
* ``shimmy-ground-presets``: every setting of the ground-run presets with default and range
  (:func:`shimmy.analyses.ground.ground_profiles.preset_fields`).
"""

from __future__ import annotations

import argparse
import importlib
import json
import re
from typing import Iterable, Sequence

from docutils import nodes
from docutils.parsers.rst import directives
from sphinx.util.docutils import SphinxDirective


def _cell(text) -> nodes.entry:
    entry = nodes.entry()
    if isinstance(text, nodes.Node):
        entry += text
    else:
        entry += nodes.paragraph(text=str(text))
    return entry


def table(header: Sequence[str], rows: Iterable[Sequence], widths: Sequence[int] | None = None) -> nodes.table:
    """A docutils table node from a header and rows of text (or nodes)."""
    rows = [list(r) for r in rows]
    tab = nodes.table(classes=["shimmy-generated"])
    group = nodes.tgroup(cols=len(header))
    tab += group
    for w in widths or [1] * len(header):
        group += nodes.colspec(colwidth=w)
    head = nodes.thead()
    row = nodes.row()
    for h in header:
        row += _cell(h)
    head += row
    group += head
    body = nodes.tbody()
    for r in rows:
        row = nodes.row()
        for value in r:
            row += _cell(value)
        body += row
    group += body
    return tab


def _literal(text: str) -> nodes.literal:
    return nodes.literal(text=text)


def _number(x) -> str:
    return f"{x:g}" if isinstance(x, (int, float)) and not isinstance(x, bool) else str(x)


class Parameters(SphinxDirective):
    option_spec = {"group": directives.unchanged}

    def run(self):
        from shimmy.model.parameters import PARAMETER_SPECS
        group = self.options.get("group")
        rows = [[_literal(s.name), s.description, s.unit or "–", _number(s.default),
                 f"{_number(s.low)} to {_number(s.high)}" + (" (integer)" if s.integer else ""), s.provenance]
                for s in PARAMETER_SPECS.values() if group in (None, s.group)]
        return [table(["name", "meaning", "unit", "default", "range", "provenance"], rows, [2, 6, 2, 2, 3, 6])]


class OperatingPoints(SphinxDirective):
    def run(self):
        from shimmy.model.configurations import OPERATING_POINTS
        band = lambda fz: "low" if fz < 250e3 else ("medium" if fz <= 450e3 else "high")  # noqa: E731
        rows = [[name, _number(V), _number(Fz / 1e3), band(Fz)] for name, (V, Fz) in OPERATING_POINTS.items()]
        return [table(["point", "V (m/s)", "Fz (kN)", "load band"], rows)]


class CalibrationTargets(SphinxDirective):
    FIXES = {"original": "k_lam (about 0.002)", "nes": "I_nes, c_nes (about 4.84 kg m², 80.1 N m s/rad)",
             "nes_pd": "I_pd (about 4.9 kg m²)"}

    def run(self):
        from shimmy.analyses.core import calibration as cal
        rows = [[_literal(config), f"Hopf points of x = 0 in V at Fz = {cal.FZ_REFERENCE / 1e3:g} kN",
                 " and ".join(f"{v:g}" for v in targets) + " m/s", self.FIXES.get(config, "")]
                for config, targets in cal.HOPF_TARGETS.items()]
        t = cal.AMPLITUDE_TARGET
        rows.append([_literal(t["config"]), f"steady torsional amplitude at V = {t['V']:g} m/s, Fz = "
                     f"{t['Fz'] / 1e3:g} kN", f"about {t['psi']:g} rad",
                     "the PD damping level (g_p and/or f, inside their ranges)"])
        return [table(["configuration", "what", "published value", "fixes"], rows, [2, 6, 3, 5])]


class Endpoints(SphinxDirective):
    def run(self):
        from shimmy.service.api import PREFIX, openapi_document
        rows = []
        for path, item in openapi_document()["paths"].items():
            for method, op in item.items():
                if method == "parameters":
                    continue
                rows.append([_literal(f"{method.upper()} {PREFIX}{path}"), op.get("summary", ""),
                             ", ".join(op.get("responses", {}))])
        return [table(["endpoint", "what", "status codes"], rows, [4, 7, 3])]


class Request(SphinxDirective):
    required_arguments = 1

    def run(self):
        from shimmy.service import schemas
        name = self.arguments[0]
        if name not in schemas.SCHEMAS:
            raise self.error(f"no request schema {name!r}; known: {', '.join(schemas.SCHEMAS)}")
        rows = [[_literal(f.name), f.kind, "yes" if f.required else "no",
                 "–" if f.default in (None, {}) else _literal(json.dumps(f.default)), f.allowed,
                 f.description + (f" ({f.unit})" if f.unit else "")] for f in schemas.SCHEMAS[name].fields]
        return [table(["field", "type", "required", "default", "allowed", "meaning"], rows, [2, 2, 1, 2, 5, 6])]


class JobStatuses(SphinxDirective):
    def run(self):
        from shimmy.service.api import openapi_document
        job = openapi_document()["components"]["schemas"]["Job"]["properties"]
        items = nodes.bullet_list()
        for title, values in (("analysis", job["analysis"]["enum"]), ("status", job["status"]["enum"])):
            para = nodes.paragraph()
            para += _literal(title)
            para += nodes.Text(": ")
            for k, v in enumerate(values):
                if k:
                    para += nodes.Text(", ")
                para += _literal(v)
            items += nodes.list_item("", para)
        return [items]


class Limits(SphinxDirective):
    def run(self):
        from shimmy.service import settings
        rows = [
            ["request body", f"{settings.MAX_BODY_BYTES} bytes", "–"],
            ["simulated time t_end", f"{settings.MAX_T_END:g} s", "–"],
            ["samples of a returned series", f"{settings.MAX_SERIES_POINTS}", "–"],
            ["collocation intervals ntst", f"{settings.MAX_NTST}", "–"],
            ["Fz slices of one map", f"{settings.MAX_MAP_SLICES}", "–"],
            ["speeds per map slice", f"{settings.MAX_MAP_SPEEDS}", "–"],
            ["values per study parameter", f"{settings.MAX_STUDY_VALUES}", "–"],
            ["diagrams per study", f"{settings.MAX_STUDY_UNITS}", "–"],
            ["jobs running at once", f"{settings.MAX_RUNNING_JOBS}", _literal("SHIMMY_MAX_RUNNING_JOBS")],
            ["jobs waiting queued", f"{settings.MAX_QUEUED_JOBS}", _literal("SHIMMY_MAX_QUEUED_JOBS")],
            ["Retry-After of a 429", f"{settings.JOB_RETRY_AFTER_SECONDS} s",
             _literal("SHIMMY_JOB_RETRY_AFTER_SECONDS")],
            ["request headers read, whole (proxy: client_header_timeout)", f"{settings.HEADER_READ_SECONDS:g} s",
             _literal("SHIMMY_HEADER_READ_SECONDS")],
            ["pause in a request body (proxy: client_body_timeout)", f"{settings.BODY_READ_SECONDS:g} s",
             _literal("SHIMMY_BODY_READ_SECONDS")],
            ["pause in reading an answer (proxy: send_timeout)", f"{settings.SEND_SECONDS:g} s",
             _literal("SHIMMY_SEND_SECONDS")],
            ["idle keep-alive connection (proxy: keepalive_timeout)", f"{settings.KEEPALIVE_SECONDS:g} s",
             _literal("SHIMMY_KEEPALIVE_SECONDS")],
            ["requests per keep-alive connection (proxy)", f"{settings.KEEPALIVE_REQUESTS}", "–"],
            ["longest answer of the app (proxy: proxy_read_timeout; gunicorn --timeout)",
             f"{settings.REQUEST_SECONDS} s", "–"],
            ["threads per web worker", f"{settings.WEB_THREADS}", _literal("SHIMMY_WEB_THREADS")],
            ["heartbeat of a job worker on another host", f"{settings.JOB_STALE_SECONDS:g} s",
             _literal("SHIMMY_JOB_STALE_SECONDS")],
            ["a job worker with no job left waits idle for the next one", f"{settings.JOB_WORKER_LINGER_SECONDS:g} s",
             _literal("SHIMMY_JOB_WORKER_LINGER_SECONDS")],
            ["requests per workbench action", f"{settings.MAX_PAGE_REQUESTS}", "–"],
            ["jobs queued or running per user", f"{settings.MAX_JOBS_PER_USER}",
             _literal("SHIMMY_MAX_JOBS_PER_USER")],
            ["jobs running at once per user", "all slots but one (1 of 2)",
             _literal("SHIMMY_MAX_RUNNING_JOBS_PER_USER")],
            ["queue places kept for users with no job waiting", "a quarter of the queue (2 of 8)",
             _literal("SHIMMY_QUEUE_RESERVED")],
            ["finished job records kept", f"{settings.JOB_RETENTION_HOURS:g} h",
             _literal("SHIMMY_JOB_RETENTION_HOURS")],
            ["job records kept at most", f"{settings.MAX_JOB_RECORDS}", _literal("SHIMMY_MAX_JOB_RECORDS")],
            ["quick computations at once per web worker", f"{settings.MAX_FAST_COMPUTATIONS}",
             _literal("SHIMMY_MAX_FAST_COMPUTATIONS")],
            ["quick computations waiting per web worker", "threads less the slots less 4 (26)", "–"],
            ["longest wait for a computation slot", f"{settings.FAST_WAIT_SECONDS:g} s",
             _literal("SHIMMY_FAST_WAIT_SECONDS")],
            ["Retry-After of a refused quick computation", f"{settings.FAST_RETRY_AFTER_SECONDS} s",
             _literal("SHIMMY_FAST_RETRY_AFTER_SECONDS")],
            ["quick computations per user and second", f"{settings.FAST_PER_USER_PER_SECOND:g}",
             _literal("SHIMMY_FAST_PER_USER_PER_SECOND")],
            ["quick computations per user in a burst", f"{settings.FAST_PER_USER_BURST:g}",
             _literal("SHIMMY_FAST_PER_USER_BURST")],
            ["sign-in attempts per address and minute", f"{settings.LOGIN_ATTEMPTS_PER_MINUTE}",
             _literal("SHIMMY_LOGIN_ATTEMPTS_PER_MINUTE")],
            ["workbench session", f"{settings.SESSION_HOURS:g} h", _literal("SHIMMY_SESSION_HOURS")],
        ]
        return [table(["limit", "value (default)", "environment variable"], rows, [6, 3, 4])]


class GroundPresets(SphinxDirective):
    def run(self):
        from shimmy.analyses.ground.ground_profiles import PRESETS, preset_fields
        rows = [[_literal(name), _literal(f["name"]), f["unit"] or "–", _number(f["default"]),
                 f"{_number(f['low'])} to {_number(f['high'])}", f["description"]]
                for name in PRESETS for f in preset_fields(name)]
        return [table(["preset", "setting", "unit", "default", "range", "meaning"], rows, [2, 3, 2, 2, 3, 6])]


class OpenAPI(SphinxDirective):
    def run(self):
        from shimmy.service.api import openapi_document
        text = json.dumps(openapi_document(), indent=1)
        block = nodes.literal_block(text, text, language="json")
        return [block]


class CommandLine(SphinxDirective):
    def run(self):
        from shimmy.cli import build_parser
        parser = build_parser()
        sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        helps = {a.dest: a.help for a in sub._get_subactions()}
        out = []
        commands = [(name, p, helps.get(name)) for name, p in sub.choices.items()]
        while commands:
            name, p, helped = commands.pop(0)
            nested = [a for a in p._actions if isinstance(a, argparse._SubParsersAction)]
            if nested:  # a group of actions (tokens create|list|revoke): each action its own entry, in order
                inner = {a.dest: a.help for a in nested[0]._get_subactions()}
                commands[:0] = [(f"{name} {action}", q, inner.get(action)) for action, q in nested[0].choices.items()]
                continue
            out.append(nodes.rubric(text=f"python -m shimmy {name}"))
            out.append(nodes.paragraph(text=helped or ""))
            usage = " ".join(p.format_usage().split())
            out.append(nodes.literal_block(usage, usage))
            rows = []
            for action in p._actions:
                if isinstance(action, argparse._HelpAction):
                    continue
                flags = ", ".join(action.option_strings) or action.dest
                if action.choices:
                    kind = "one of " + ", ".join(map(str, action.choices))
                elif action.nargs == 0:
                    kind = "flag"
                else:
                    kind = action.metavar or "value"
                default = "–" if action.default in (None, False) or action.required else _number(action.default)
                rows.append([_literal(flags), "yes" if action.required else "no", kind, default, action.help or ""])
            out.append(table(["option", "required", "takes", "default", "meaning"], rows, [3, 1, 3, 2, 7]))
        return out


_ABS = re.compile(r"(?<![|`\\\w])\|([^|`\n]{1,40}?)\|(?![|`A-Za-z0-9])")


def escape_absolute_values(app, what, name, obj, options, lines) -> None:
    """Docstrings write absolute values as |x| (|dpsi|^(1/2) dpsi): escaped, so that reST does not
    take them for substitutions. Literal text (between double backquotes) and literal blocks are left."""
    in_block = False
    for k, line in enumerate(lines):
        stripped = line.strip()
        if in_block and stripped and not line.startswith((" ", "\t")):
            in_block = False
        if not in_block:
            parts = line.split("``")
            parts[::2] = [_ABS.sub(r"\\|\1\\|", part) for part in parts[::2]]
            lines[k] = "``".join(parts)
        if stripped.endswith("::"):
            in_block = True


def _lookup(dotted: str):
    """The Python object named ``dotted`` (module, then attributes), or None."""
    parts = dotted.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
        except ImportError:
            continue
        rest = parts[cut:]
        for k, attr in enumerate(rest):
            if hasattr(obj, attr):
                obj = getattr(obj, attr)
            elif k == len(rest) - 1 and isinstance(obj, type) and any(
                    attr in getattr(c, "__annotations__", {}) for c in obj.__mro__):
                return _Field(obj, attr)  # a dataclass field without a default: no class attribute
            else:
                return None
        return obj
    return None


class _Field(tuple):
    """(class, name) of an annotated attribute that has no value on the class."""

    def __new__(cls, owner, name):
        return super().__new__(cls, (owner, name))


def _identity(obj):
    return (id(obj[0]), obj[1]) if isinstance(obj, _Field) else id(obj)


def resolve_alias(app, env, node, contnode):
    """A Python reference to an object documented under another of its names (``shimmy.simulate`` is
    documented, ``shimmy.analyses.core.simulation.simulate`` is referenced, or the reverse; a name relative
    to the current module): resolved to the documented name of the same object. A reference to
    something that does not exist or is not documented under any name stays unresolved (and fails the
    nitpicky build)."""
    if node.get("refdomain") != "py":
        return None
    target = node["reftarget"].lstrip("~.")
    module, cls = node.get("py:module"), node.get("py:class")
    candidates = [target]
    if module:
        candidates += [f"{module}.{cls}.{target}" if cls else None, f"{module}.{target}"]
        parent = module.rsplit(".", 1)[0]
        candidates.append(f"{parent}.{target}")
    domain = env.get_domain("py")
    documented = getattr(env, "_shimmy_documented", None)
    if documented is None:
        documented = {}
        for name in domain.objects:
            obj = _lookup(name)
            if obj is not None and (isinstance(obj, _Field) or not isinstance(obj, (int, float, str, tuple, dict,
                                                                                    bool))):
                documented.setdefault(_identity(obj), name)
        env._shimmy_documented = documented
    for candidate in filter(None, candidates):
        if candidate in domain.objects:
            name = candidate
        else:
            obj = _lookup(candidate)
            name = documented.get(_identity(obj)) if obj is not None else None
        if name is None:
            continue
        kind = domain.objects[name].objtype
        role = {"function": "func", "method": "meth", "class": "class", "exception": "exc", "module": "mod",
                "attribute": "attr", "data": "data", "property": "attr"}.get(kind, "obj")
        return domain.resolve_xref(env, node["refdoc"], app.builder, role, name, node, contnode)
    return None


def setup(app):
    app.connect("autodoc-process-docstring", escape_absolute_values)
    app.connect("missing-reference", resolve_alias)
    for name, cls in (("shimmy-parameters", Parameters), ("shimmy-operating-points", OperatingPoints),
                      ("shimmy-calibration-targets", CalibrationTargets),
                      ("shimmy-endpoints", Endpoints), ("shimmy-request", Request),
                      ("shimmy-job-statuses", JobStatuses), ("shimmy-limits", Limits), ("shimmy-openapi", OpenAPI),
                      ("shimmy-cli", CommandLine), ("shimmy-ground-presets", GroundPresets)):
        app.add_directive(name, cls)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
