"""Command line: ``python -m shimmy COMMAND ...`` (``python -m shimmy --help`` lists the commands).

Results go to stdout (JSON with ``--json``, a short table otherwise). Bad input exits
with status 2 and a message on stderr naming the field, its value and what is allowed.
The limits of every option that the API also takes (t_end, resolution, ntst, ...) are the
API's, read from its request schemas. Long commands report progress on stderr: a bar on a
terminal, plain lines otherwise (``--progress``).

Commands that the HTTP API also answers read and fill its result cache (``SHIMMY_CACHE_DIR``, the
store its job workers and the workbench share), by the API's canonical requests: a question
answered anywhere is answered everywhere. ``--no-cache`` computes without the cache; the JSON's
``"cache"`` (hit, miss or off) and the text's last line say where an answer came from.

Each command's options sit next to the handler that runs it, in ``shimmy.cli.commands``
(one module per group of commands); ``shimmy.cli.common`` holds what they share, and
``shimmy.cli.answers`` what the commands on the cache share.
"""

from __future__ import annotations

import argparse
import sys
import textwrap
from typing import Sequence

from ..continuation.errors import InvalidInputError
from ..errors import EXPECTED_ERRORS, GeometryError
from ..service.settings import CacheDirectoryError, cache_dir_setting
from .commands import decisions, diagrams, ground, maps, margins, model, point, service
from .common import EXIT_BAD_INPUT, EXIT_FAILED

__all__ = ["build_parser", "main"]

DESCRIPTION = """\
Nose-landing-gear shimmy and its suppression by a torsional nonlinear energy sink (NES) and a
particle damper (PD), in four configurations: original, nes, pd, nes_pd. Every command prints a
short table, or JSON with --json; bad input exits with status 2 and a message naming the field,
its value and what is allowed. Units are SI: V in m/s, Fz in N."""

#: What --help says of the cache: which commands use it and where it is.
CACHE = """The commands the HTTP API also answers ({commands}) share its result cache with the API's job
workers and the workbench: the directory SHIMMY_CACHE_DIR, by default a per-user folder in the
temporary directory (now: {where}). A question answered there is answered here at once and the
other way round; the JSON's "cache" (hit, miss or off) and the text's last line say where the
answer came from. --no-cache computes without reading or writing the cache."""

EPILOG = """\
examples:
  python -m shimmy params
  python -m shimmy hopf --config nes --Fz 150000
  python -m shimmy simulate --config original --V 50 --Fz 850000 --t-end 60
  python -m shimmy margins --config original --V 50 --Fz 550000 --direction psi
  python -m shimmy margin-map --config nes --n-v 20 --n-fz 10
  python -m shimmy map --config nes_pd --resolution 10 --json > map.json
  python -m shimmy study --param e_p --values 0.0005,0.001,0.005 --configs nes,nes_pd

'python -m shimmy COMMAND --help' describes a command and its options."""

#: The groups of commands, in the order ``--help`` lists their commands.
GROUPS = (point, margins, ground, diagrams, maps, decisions, model, service)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m shimmy", description=DESCRIPTION, epilog=EPILOG,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for group in GROUPS:
        group.add_parsers(commands)
    cached = [name for name, p in commands.choices.items() if any(a.dest == "no_cache" for a in p._actions)]
    cache = CACHE.format(commands=", ".join(cached), where=cache_dir_setting())
    parser.description += "\n\n" + textwrap.fill(" ".join(cache.split()), 99)
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
    except CacheDirectoryError as exc:
        print(f"error: {exc}; or run with --no-cache", file=sys.stderr)
        return EXIT_BAD_INPUT
    except BrokenPipeError:  # stdout closed early (| head): not an error of ours
        return 0
    except OSError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
