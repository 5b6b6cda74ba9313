"""``python -m clew_ros.cli.parameter_tables [--update FILE | --check FILE]``: README's parameter tables.

The tables are generated from the one parameter specification
(:mod:`clew_ros.core.parameters`). Without options they are printed; with
``--update README.md`` they are rewritten between their markers; with
``--check README.md`` the exit code is 1 when they are out of date.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from clew_ros.core.parameters import marked_tables, update_markdown


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m clew_ros.cli.parameter_tables", description=__doc__.split("\n")[0])
    parser.add_argument("--update", metavar="FILE", type=Path, help="rewrite the generated tables of FILE in place")
    parser.add_argument("--check", metavar="FILE", type=Path, help="exit 1 when the tables of FILE are out of date")
    args = parser.parse_args(argv)
    if args.update is None and args.check is None:
        print(marked_tables())
        return 0
    path = args.update or args.check
    text = path.read_text(encoding="utf-8")
    try:
        updated = update_markdown(text)
    except ValueError as error:
        print(f"{path}: {error}", file=sys.stderr)
        return 2
    if args.check is not None:
        if updated != text:
            print(
                f"{path}: the parameter tables are out of date; run "
                f"python -m clew_ros.cli.parameter_tables --update {path}",
                file=sys.stderr,
            )
            return 1
        return 0
    if updated != text:
        path.write_text(updated, encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
