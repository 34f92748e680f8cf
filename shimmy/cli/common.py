"""What every command shares: the common options (``--json``, ``--set``, ``--material``,
``--progress``), the design they give, the API's limits of an option, number lists, the output
(JSON or text) and the progress bar on stderr."""

from __future__ import annotations

import argparse
import json
import sys
from contextlib import contextmanager
from typing import Any, Callable, Iterator, Sequence

from ..errors import InvalidParameterError
from ..model.configurations import CONFIGURATION_NAMES
from ..model.parameters import DIAGRAM_V_RANGE, FZ_RANGE, MATERIALS, Parameters, check_number
from ..service.schemas import SCHEMAS

EXIT_BAD_INPUT = 2
EXIT_FAILED = 1

#: The configurations a ``--config`` takes.
CONFIGS = list(CONFIGURATION_NAMES)


def limit(analysis: str, name: str, value: Any) -> float | int:
    """``value`` checked against the limits the API gives field ``name`` of ``analysis`` (one definition)."""
    f = SCHEMAS[analysis].field(name)
    number = check_number(name, value, f.low, f.high, f.unit, f.kind == "integer")
    return int(number) if f.kind == "integer" else number


def add_field(p: argparse.ArgumentParser, analysis: str, flag: str, help: str, limits: bool = False,
              **kwargs) -> None:
    """Option ``flag`` (``--t-end``) with the default, and the choices, the API gives its field (``t_end``) in
    the request of ``analysis``; ``limits`` adds the field's range to the help, " (LOW to HIGH UNIT)"."""
    f = SCHEMAS[analysis].field(flag.lstrip("-").replace("-", "_"))
    default = ",".join(f.default) if isinstance(f.default, list) else f.default
    if f.kind == "string" and f.choices:
        kwargs.setdefault("choices", f.choices)
    if limits:
        help += f" ({f.low:g} to {f.high:g}{' ' + f.unit if f.unit else ''})"
    p.add_argument(flag, default=default, help=help, **kwargs)


def add_plane(p: argparse.ArgumentParser, analysis: str | None = None, loads: bool = True) -> None:
    """``--v-min``, ``--v-max`` and, with ``loads``, ``--fz-min``, ``--fz-max``: their defaults those of the
    API's request of ``analysis``, or without one those of a diagram (``DIAGRAM_V_RANGE``, ``FZ_RANGE``)."""
    box = {"--v-min": ("lowest speed (m/s)", DIAGRAM_V_RANGE[0]),
           "--v-max": ("highest speed (m/s)", DIAGRAM_V_RANGE[1]),
           "--fz-min": ("lowest load (N)", FZ_RANGE[0]), "--fz-max": ("highest load (N)", FZ_RANGE[1])}
    for flag, (help, default) in list(box.items())[:4 if loads else 2]:
        if analysis is None:
            p.add_argument(flag, default=default, help=help)
        else:
            add_field(p, analysis, flag, help)


def parse_sets(items: Sequence[str] | None) -> dict[str, str]:
    overrides: dict[str, str] = {}
    for item in items or []:
        name, sep, value = item.partition("=")
        if not sep or not name:
            raise InvalidParameterError("--set", item, "NAME=VALUE with NAME from 'python -m shimmy params'",
                                        "is not of the form NAME=VALUE")
        overrides[name.strip()] = value.strip()
    return overrides


def params(args) -> Parameters:
    """The design of ``--material`` and ``--set``."""
    design = Parameters()
    if getattr(args, "material", None):
        design = design.with_material(args.material)
    return design.with_overrides(parse_sets(args.set))


def float_list(name: str, text: str) -> list[float]:
    items = [t.strip() for t in str(text).split(",") if t.strip()]
    try:
        return [float(t) for t in items]
    except ValueError:
        raise InvalidParameterError(name, text, "comma-separated numbers, e.g. 0.0005,0.001,0.005") from None


def names(text: str | None) -> list[str] | None:
    return None if text is None else [n.strip() for n in str(text).split(",") if n.strip()]


def emit(payload: dict[str, Any], as_json: bool, text: str) -> None:
    if as_json:
        json.dump(payload, sys.stdout, indent=2, allow_nan=False)
        sys.stdout.write("\n")
    else:
        print(text)


class ProgressBar:
    """Progress on stderr: a one-line bar on a terminal, plain log lines anywhere else (a script, a
    notebook, a CI log), or nothing. ``mode``: "auto" (bar on a terminal, lines otherwise), "bar",
    "log" or "none". Lines are written when the message changes or the fraction moves by 5 %."""

    def __init__(self, stream=None, width: int = 30, mode: str = "auto"):
        self.stream = stream or sys.stderr
        self.width = width
        if mode == "auto":
            mode = "bar" if self.stream.isatty() else "log"
        self.mode = mode
        self.enabled = mode == "bar"
        self._last: tuple[float, str] | None = None

    def __call__(self, fraction: float, message: str) -> None:
        fraction = min(max(fraction, 0.0), 1.0)
        if self.mode == "log":
            if self._last is None or message != self._last[1] or fraction - self._last[0] >= 0.05 or fraction == 1:
                self.stream.write(f"[{100 * fraction:5.1f} %] {message}\n")
                self.stream.flush()
                self._last = (fraction, message)
            return
        if not self.enabled:
            return
        filled = int(round(self.width * fraction))
        self.stream.write(f"\r[{'#' * filled}{'.' * (self.width - filled)}] {100 * fraction:5.1f} % {message[:50]:<50}")
        self.stream.flush()

    def close(self) -> None:
        if self.enabled:
            self.stream.write("\r" + " " * (self.width + 60) + "\r")
            self.stream.flush()


@contextmanager
def progress(args) -> Iterator[ProgressBar]:
    """The bar ``--progress`` asks for, cleared at the end (also on an error)."""
    bar = ProgressBar(mode=getattr(args, "progress", "auto"))
    try:
        yield bar
    finally:
        bar.close()


class Formatter(argparse.ArgumentDefaultsHelpFormatter):
    """Defaults shown where there is one (not "default: None" on a flag or an optional file)."""

    def _get_help_string(self, action):
        if action.default in (None, False) or action.default is argparse.SUPPRESS:
            return action.help
        return super()._get_help_string(action)


def add_command(commands, name: str, help: str, handler: Callable[[Any], int]) -> argparse.ArgumentParser:
    """A command's parser: its ``--help`` opens with its description and shows the defaults; ``handler(args)``
    runs it and gives the exit status."""
    p = commands.add_parser(name, help=help, description=help[0].upper() + help[1:] + ".", formatter_class=Formatter)
    p.set_defaults(handler=handler)
    return p


def add_common(p: argparse.ArgumentParser, design: bool = True) -> None:
    p.add_argument("--json", action="store_true", help="write JSON to stdout")
    if design:
        p.add_argument("--set", action="append", metavar="NAME=VALUE",
                       help="override a parameter (repeatable); see 'params' for names and ranges")
        p.add_argument("--material", choices=sorted(MATERIALS), help="particle-damper material preset")


def add_progress(p: argparse.ArgumentParser) -> None:
    p.add_argument("--progress", choices=("auto", "bar", "log", "none"), default="auto",
                   help="progress on stderr: a bar (bar), plain lines that work in scripts and notebooks (log), "
                        "nothing (none); auto draws the bar on a terminal and writes lines otherwise")


def add_config(p: argparse.ArgumentParser, extra: Sequence[str] = (), help: str = "configuration") -> None:
    p.add_argument("--config", required=True, choices=[*CONFIGS, *extra], help=help)


def add_operating_point(p: argparse.ArgumentParser) -> None:
    """``--config``, ``--V``, ``--Fz`` (required) and the common options."""
    add_config(p)
    p.add_argument("--V", required=True, help="forward speed (m/s)")
    p.add_argument("--Fz", required=True, help="vertical load (N)")
    add_common(p)
