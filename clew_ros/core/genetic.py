"""A small real-coded genetic algorithm that evaluates whole populations at once.

Minimises ``evaluate(population) -> fitness`` where ``population`` is
``(P, D)``. Tournament selection, blend (BLX-alpha) crossover, Gaussian
mutation, elitism. Optionally the first gene is a category index (for EXPLORE's
choice of landmark and grasp), mutated by re-drawing it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

__all__ = ["GeneticResult", "GeneticSettings", "minimize"]


@dataclass(frozen=True)
class GeneticSettings:
    """Sizes and rates of the genetic algorithm."""

    population: int = 24
    generations: int = 12
    elite: int = 2
    tournament: int = 3
    crossover_rate: float = 0.9
    mutation_rate: float = 0.25  # per gene
    mutation_scale: float = 0.6  # standard deviation of a mutation, in gene units (rad)
    stall_generations: int = 5  # stop after this many generations without improvement
    #: blend (BLX-alpha) crossover: a child gene is drawn from its parents' interval widened by this share of
    #: its width each way (dimensionless), so children can leave the parents' box and the population keeps spreading
    blend_alpha: float = 0.3


@dataclass
class GeneticResult:
    genes: np.ndarray  # (D,) best individual
    fitness: float
    evaluations: int
    generations: int
    population: np.ndarray  # final population (P, D)
    population_fitness: np.ndarray  # (P,)


def minimize(
    evaluate: Callable[[np.ndarray], np.ndarray],
    initial: np.ndarray,
    rng: np.random.Generator,
    settings: GeneticSettings = GeneticSettings(),
    *,
    target: float = -np.inf,
    categories: int = 0,
    should_stop: Callable[[], bool] = lambda: False,
) -> GeneticResult:
    """Minimise ``evaluate`` starting from the population ``initial`` ``(P, D)``.

    Stops after ``settings.generations`` generations, when the best fitness is
    ``<= target``, after ``settings.stall_generations`` without improvement, or
    when ``should_stop()`` is true. With ``categories > 0`` gene 0 is an
    integer in ``[0, categories)``. One island of :func:`minimize_islands`
    (the same draws, the same result).
    """
    return minimize_islands(
        lambda population, _islands: evaluate(population[0])[None],
        np.asarray(initial, dtype=float)[None],
        rng,
        settings,
        targets=np.array([target]),
        categories=categories,
        should_stop=should_stop,
    )[0]


def minimize_islands(
    evaluate: Callable[[np.ndarray, np.ndarray], np.ndarray],
    initial: np.ndarray,
    rng: np.random.Generator,
    settings: GeneticSettings = GeneticSettings(),
    *,
    targets: np.ndarray | None = None,
    categories: int = 0,
    should_stop: Callable[[], bool] = lambda: False,
) -> list[GeneticResult]:
    """Minimise ``I`` independent problems at once, one population (island) each: ``initial`` is
    ``(I, P, D)``; ``evaluate(population (A, C, D), islands (A,))`` returns the fitness ``(A, C)`` of
    the islands still running, so that their individuals are evaluated in one batch (the parallel
    genetic algorithm of the 1998 Ariadne's Clew paper, in lockstep). Each island stops on its own
    (its ``targets`` entry reached, or stalled); all stop after ``settings.generations`` or when
    ``should_stop()`` is true."""
    population = np.array(initial, dtype=float)
    islands, size, _dims = population.shape  # (I, P, D)
    if not 0 <= settings.elite < size:
        raise ValueError(f"elite: expected 0 <= elite < population ({size}), got {settings.elite}")
    targets = np.full(islands, -np.inf) if targets is None else np.broadcast_to(targets, (islands,))
    everyone = np.arange(islands)
    fitness = np.asarray(evaluate(population, everyone), dtype=float).reshape(islands, size)
    evaluations = np.full(islands, size)
    best_fitness = np.fmin.reduce(fitness, axis=1)  # NaN (a failed evaluation) never counts as best
    stall = np.zeros(islands, dtype=int)
    generations = np.zeros(islands, dtype=int)
    elite_count = settings.elite
    children_count = size - elite_count
    rows_all = np.arange(islands)[:, None]
    limit = settings.stall_generations
    for _generation in range(settings.generations):
        go = ~(best_fitness <= targets) & (stall < limit)
        every = bool(go.all())  # the usual case: slices (views), not copies
        if not (every or go.any()) or should_stop():
            break
        running = everyone if every else everyone[go]
        pick = slice(None) if every else running
        count = len(running)
        pool, scores = population[pick], fitness[pick]
        rows = rows_all[:count]
        order = np.argsort(scores, axis=1, kind="stable")[:, :elite_count]
        elite = pool[rows, order]
        children = _children(pool, scores, rng, settings, categories)
        child_fitness = np.asarray(evaluate(children, running), dtype=float).reshape(count, children_count)
        elite_fitness = scores[rows, order]
        population[pick, :elite_count] = elite
        population[pick, elite_count:] = children
        fitness[pick, :elite_count] = elite_fitness
        fitness[pick, elite_count:] = child_fitness
        evaluations[pick] += children_count
        generations[pick] += 1
        lowest = np.fmin.reduce(fitness[pick], axis=1)
        improved = lowest < best_fitness[pick] - 1e-12
        best_fitness[pick] = np.where(improved, lowest, best_fitness[pick])
        stall[pick] = (stall[pick] + 1) * ~improved
    best = np.argmin(fitness, axis=1)
    return [
        GeneticResult(
            population[i, best[i]].copy(),
            float(fitness[i, best[i]]),
            int(evaluations[i]),
            int(generations[i]),
            population[i],
            fitness[i],
        )
        for i in range(islands)
    ]


def _children(
    pool: np.ndarray, scores: np.ndarray, rng: np.random.Generator, settings: GeneticSettings, categories: int
) -> np.ndarray:
    """The ``P - elite`` children ``(I, P - elite, D)`` of each island of ``pool (I, P, D)`` (fitness
    ``scores (I, P)``): tournament selection, blend crossover, Gaussian mutation; with ``categories``,
    gene 0 comes from either parent or is redrawn."""
    count, size, dims = pool.shape
    children_count = size - settings.elite
    rows = np.arange(count)[:, None]
    parents = _tournament(scores, rng, 2 * children_count, settings.tournament)
    mothers = pool[rows, parents[:, :children_count]]
    fathers = pool[rows, parents[:, children_count:]]
    u = rng.uniform(-settings.blend_alpha, 1 + settings.blend_alpha, size=(count, children_count, dims))
    children: np.ndarray = mothers + u * (fathers - mothers)
    keep = rng.random((count, children_count)) >= settings.crossover_rate
    children[keep] = mothers[keep]
    mutate = rng.random((count, children_count, dims)) < settings.mutation_rate
    children += mutate * rng.normal(0.0, settings.mutation_scale, size=(count, children_count, dims))
    if categories:
        chosen = rng.random((count, children_count)) < 0.5
        children[..., 0] = np.where(chosen, mothers[..., 0], fathers[..., 0])
        redraw = rng.random((count, children_count)) < settings.mutation_rate
        children[redraw, 0] = rng.integers(0, categories, size=int(redraw.sum()))
    return children


def _tournament(fitness: np.ndarray, rng: np.random.Generator, count: int, size: int) -> np.ndarray:
    """``count`` winners per island of tournaments of ``size`` over ``fitness (I, P)``: indices ``(I, count)``."""
    contenders = rng.integers(0, fitness.shape[1], size=(fitness.shape[0], count, size))
    rows = np.arange(fitness.shape[0])[:, None]
    scores = fitness[rows[:, :, None], contenders]
    winners: np.ndarray = contenders[rows, np.arange(count)[None, :], np.argmin(scores, axis=2)]
    return winners
