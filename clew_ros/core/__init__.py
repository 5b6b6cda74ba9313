"""The Ariadne's Clew Algorithm for manipulation (the paper, *On Manipulation Planning*), over a space.

Nothing here looks at a world: the algorithm asks a :class:`~clew_ros.core.space.Space` (the planar world's is
:class:`clew_ros.planar.space.PlanarSpace`). numpy only, no ROS.

==========================================================  =================  ==================================
paper                                                       module             what
==========================================================  =================  ==================================
what the ACA asks of a world; a run's shared state          ``space``          ``Space``, ``PlanningSpace``,
                                                                               ``Mode``, ``PlanningContext``
1.3.1 Manhattan paths, 1.3.3 bouncing                       ``manhattan``      ``bounce``, ``ManhattanPaths``
"we have used genetic algorithms"                           ``genetic``        ``minimize``, ``minimize_islands``
1.3.2 f_a, f_b; 1.3.4 SEARCH's do-while loop                ``search``         ``local_search``, ``SearchJob``
1.2, 1.3.4 EXPLORE                                          ``explore``        ``Explorer``
1.2 the landmark tree, the history of a landmark            ``tree``           ``LandmarkTree``, ``Segment``
1.2 ARIADNE'S CLEW                                          ``clew``           ``plan``, ``PlanResult``
(addition) the improvement's generic parts                  ``improve``        ``better``, ``WorkBudget``,
                                                                               ``pruned_path``, ``joined_regrasps``,
                                                                               ``shortcut_path``
settings, outcomes (when each is given), termination        ``settings``       ``PlannerSettings``, ``Outcome``
the parameters of the contract (world, planner, node)       ``parameters``     their specification and limits
==========================================================  =================  ==================================

Every departure from the paper: docs/algorithm.md.
"""
