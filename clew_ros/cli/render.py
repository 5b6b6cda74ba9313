"""``clew_render``: render a plan or recording to an image. Not yet implemented."""

import sys

EXIT_NOT_IMPLEMENTED = 3


def main(argv: list[str] | None = None) -> int:
    """Report that ``clew_render`` is not built yet; return exit code 3."""
    del argv  # no options yet
    print("clew_render: not yet implemented (see issue N)", file=sys.stderr)
    return EXIT_NOT_IMPLEMENTED


if __name__ == "__main__":
    raise SystemExit(main())
