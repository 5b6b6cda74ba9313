"""Command-line tools: ``clew_plan``, ``clew_replay`` and ``clew_render``.

Each module has a ``main(argv=None) -> int`` used as a console script; only
these tools print.
"""
