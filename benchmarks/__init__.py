"""Benchmark suite of clew_ros (not installed; run from the repository root).

``python -m benchmarks.run`` runs the suite and writes JSON, CSV and a plot;
see ``docs/benchmarks.md``. Modules:

* :mod:`benchmarks.worlds`: the worlds (``config/*.yaml`` and generated families);
* :mod:`benchmarks.worker`: one world's planner runs, in a subprocess of its own;
* :mod:`benchmarks.throughput`: collision-test and free-interval throughput;
* :mod:`benchmarks.peer`: OMPL RRTConnect against the project on transit sub-problems;
* :mod:`benchmarks.profile`: cProfile of one planner run;
* :mod:`benchmarks.plot`: median time against joints and obstacles;
* :mod:`benchmarks.generated`: the generated families of :mod:`clew_ros.worlds` as benchmark worlds;
* :mod:`benchmarks.families_run`: the planner on those families, a table per family next to figure1
  (``python -m benchmarks.families_run``, apart from :mod:`benchmarks.run`).
"""
