"""The ``duckie`` command: the course's tools for students and instructors.

Errors the user can fix are printed as one sentence on stderr, without a traceback, and the
command exits with status 1 (2 for a badly formed command line, as argparse does).
"""

from __future__ import annotations

import argparse
import sys
from typing import List, Optional

from duckielib.errors import DuckielibError, NotBuiltError

__all__ = ["main"]


def _bench(args: argparse.Namespace) -> int:
    from duckielib.bench import BENCHMARKS, run_benchmark

    if args.name is None:
        for name, (_, description) in sorted(BENCHMARKS.items()):
            print(f"{name}: {description}")
        return 0
    for figure, value in run_benchmark(args.name):
        print(f"{figure}: {value}", flush=True)
    return 0


def _mission(args: argparse.Namespace) -> int:
    raise NotBuiltError(
        "The mission runner (the square-then-circle task in the simulator) is not built yet; "
        "see the README's status section for what works today."
    )


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="duckie",
        description="Tools of the Duckiebot ROS course.",
    )
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    mission = commands.add_parser(
        "mission", help="drive the square-then-circle task in the simulator"
    )
    mission.add_argument("--out", default="runs/latest", help="folder for the bag, plot, summary")
    mission.set_defaults(handler=_mission)

    bench = commands.add_parser("bench", help="run a benchmark and print its figures")
    bench.add_argument("name", nargs="?", help="benchmark to run; omit to list them")
    bench.set_defaults(handler=_bench)
    return parser


def main(argv: Optional[List[str]] = None) -> int:
    """Run the ``duckie`` command with ``argv`` (default: the process's arguments)."""
    args = _parser().parse_args(argv)
    try:
        return args.handler(args)
    except DuckielibError as error:
        print(f"duckie: {error}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("duckie: interrupted.", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
