"""Benchmark suite of clew_ros (not installed; run from the repository root).

One entry: ``python -m benchmarks COMMAND [ARGS]`` (:mod:`benchmarks.__main__`; ``python -m benchmarks`` lists
the commands and the module each runs); ``python -m benchmarks compare --baseline REV COMMAND [ARGS]`` compares
two revisions on any of them (:mod:`benchmarks.compare`). See ``docs/benchmarks.md``. Modules that are not
commands:

* :mod:`benchmarks.worlds`: the benchmark worlds (``config/*.yaml`` and the ``joints_N`` / ``obstacles_M``
  scaling series);
* :mod:`benchmarks.generated`: the generated families of :mod:`clew_ros.worlds` as benchmark worlds;
* :mod:`benchmarks.joint_grid`: the joint-space lattice of the grid reference;
* :mod:`benchmarks.plot`: median time against joints and obstacles;
* :mod:`benchmarks.report`: the header and files of the comparison tables.
"""
