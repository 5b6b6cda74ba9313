"""Command-line tools: ``clew_plan``, ``clew_replay``, ``clew_render`` and ``clew_world``.

Each module has a ``main(argv=None) -> int`` used as a console script; only
these tools print.
"""
