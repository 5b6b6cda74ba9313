"""``clew_replay``: replay a recorded run. Not yet implemented."""

import sys

EXIT_NOT_IMPLEMENTED = 3


def main(argv: list[str] | None = None) -> int:
    """Report that ``clew_replay`` is not built yet; return exit code 3."""
    del argv  # no options yet
    print("clew_replay: not yet implemented (see issue N)", file=sys.stderr)
    return EXIT_NOT_IMPLEMENTED


if __name__ == "__main__":
    raise SystemExit(main())
