"""Command line: ``python -m shimmy COMMAND ...`` (``python -m shimmy --help`` lists the commands).

Results go to stdout (JSON with ``--json``, a short table otherwise). Bad input exits
with status 2 and a message on stderr naming the field, its value and what is allowed.
The limits of every option that the API also takes (t_end, resolution, ntst, ...) are the
API's, read from its request schemas. Long commands report progress on stderr: a bar on a
terminal, plain lines otherwise (``--progress``).

Each command's options sit next to the handler that runs it, in ``shimmy.cli.commands``
(one module per group of commands); ``shimmy.cli.common`` holds what they share.
"""

from __future__ import annotations

import argparse
import sys
from typing import Sequence

from ..continuation.errors import InvalidInputError
from ..errors import EXPECTED_ERRORS, GeometryError
from .commands import decisions, diagrams, ground, maps, model, point
from .common import EXIT_BAD_INPUT, EXIT_FAILED

__all__ = ["build_parser", "main"]

DESCRIPTION = """\
Nose-landing-gear shimmy and its suppression by a torsional nonlinear energy sink (NES) and a
particle damper (PD), in four configurations: original, nes, pd, nes_pd. Every command prints a
short table, or JSON with --json; bad input exits with status 2 and a message naming the field,
its value and what is allowed. Units are SI: V in m/s, Fz in N."""

EPILOG = """\
examples:
  python -m shimmy params
  python -m shimmy hopf --config nes --Fz 150000
  python -m shimmy simulate --config original --V 50 --Fz 850000 --t-end 60
  python -m shimmy map --config nes_pd --resolution 10 --json > map.json
  python -m shimmy study --param e_p --values 0.0005,0.001,0.005 --configs nes,nes_pd

'python -m shimmy COMMAND --help' describes a command and its options."""

#: The groups of commands, in the order ``--help`` lists their commands.
GROUPS = (point, ground, diagrams, maps, decisions, model)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m shimmy", description=DESCRIPTION, epilog=EPILOG,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for group in GROUPS:
        group.add_parsers(commands)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.handler(args)
    except (InvalidInputError, GeometryError) as exc:  # InvalidParameterError derives from the first
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except EXPECTED_ERRORS as exc:
        print(f"failed: {exc}", file=sys.stderr)
        return EXIT_FAILED
    except BrokenPipeError:  # stdout closed early (| head): not an error of ours
        return 0
    except OSError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
