"""A small real-coded genetic algorithm that evaluates whole populations at once.

Minimises ``evaluate(population) -> fitness`` where ``population`` is
``(P, D)``. Tournament selection, blend (BLX-alpha) crossover, Gaussian
mutation, elitism. Optionally the first gene is a category index (for EXPLORE's
choice of landmark and grasp), mutated by re-drawing it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

__all__ = ["GeneticSettings", "GeneticResult", "minimize"]


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


@dataclass
class GeneticResult:
    genes: np.ndarray  # (D,) best individual
    fitness: float
    evaluations: int
    generations: int
    population: np.ndarray  # final population (P, D)
    population_fitness: np.ndarray  # (P,)


def minimize(evaluate: Callable[[np.ndarray], np.ndarray], initial: np.ndarray, rng: np.random.Generator,
             settings: GeneticSettings = GeneticSettings(), *, target: float = -np.inf,
             categories: int = 0, should_stop: Callable[[], bool] = lambda: False) -> GeneticResult:
    """Minimise ``evaluate`` starting from the population ``initial`` ``(P, D)``.

    Stops after ``settings.generations`` generations, when the best fitness is
    ``<= target``, after ``settings.stall_generations`` without improvement, or
    when ``should_stop()`` is true. With ``categories > 0`` gene 0 is an
    integer in ``[0, categories)``. One island of :func:`minimize_islands`
    (the same draws, the same result).
    """
    return minimize_islands(lambda population, _islands: evaluate(population[0])[None],
                            np.asarray(initial, dtype=float)[None], rng, settings, targets=np.array([target]),
                            categories=categories, should_stop=should_stop)[0]


def minimize_islands(evaluate: Callable[[np.ndarray, np.ndarray], np.ndarray], initial: np.ndarray,
                     rng: np.random.Generator, settings: GeneticSettings = GeneticSettings(), *,
                     targets: np.ndarray | None = None, categories: int = 0,
                     should_stop: Callable[[], bool] = lambda: False) -> list[GeneticResult]:
    """Minimise ``I`` independent problems at once, one population (island) each: ``initial`` is
    ``(I, P, D)``; ``evaluate(population (A, C, D), islands (A,))`` returns the fitness ``(A, C)`` of
    the islands still running, so that their individuals are evaluated in one batch (the parallel
    genetic algorithm of the 1998 Ariadne's Clew paper, in lockstep). Each island stops on its own
    (its ``targets`` entry reached, or stalled); all stop after ``settings.generations`` or when
    ``should_stop()`` is true."""
    population = np.array(initial, dtype=float)
    islands, size, dims = population.shape
    targets = np.full(islands, -np.inf) if targets is None else np.broadcast_to(targets, (islands,))
    everyone = np.arange(islands)
    fitness = np.asarray(evaluate(population, everyone), dtype=float).reshape(islands, size)
    evaluations = np.full(islands, size)
    best_fitness = fitness.min(axis=1)
    stall = np.zeros(islands, dtype=int)
    generations = np.zeros(islands, dtype=int)
    elite_count = settings.elite
    children_count = size - elite_count
    alpha = 0.3
    for _generation in range(settings.generations):
        running = everyone[(best_fitness > targets) & (stall < settings.stall_generations)]
        if not len(running) or should_stop():
            break
        count = len(running)
        order = np.argsort(fitness[running], axis=1, kind="stable")[:, :elite_count]
        elite = np.take_along_axis(population[running], order[:, :, None], axis=1)
        parents = _tournament(fitness[running], rng, 2 * children_count, settings.tournament)
        mothers = np.take_along_axis(population[running], parents[:, :children_count, None], axis=1)
        fathers = np.take_along_axis(population[running], parents[:, children_count:, None], axis=1)
        u = rng.uniform(-alpha, 1 + alpha, size=(count, children_count, dims))
        children = mothers + u * (fathers - mothers)
        keep = rng.random((count, children_count)) >= settings.crossover_rate
        children[keep] = mothers[keep]
        mutate = rng.random((count, children_count, dims)) < settings.mutation_rate
        children += mutate * rng.normal(0.0, settings.mutation_scale, size=(count, children_count, dims))
        if categories:
            pick = rng.random((count, children_count)) < 0.5
            children[..., 0] = np.where(pick, mothers[..., 0], fathers[..., 0])
            redraw = rng.random((count, children_count)) < settings.mutation_rate
            children[redraw, 0] = rng.integers(0, categories, size=int(redraw.sum()))
        child_fitness = np.asarray(evaluate(children, running), dtype=float).reshape(count, children_count)
        evaluations[running] += children_count
        generations[running] += 1
        population[running] = np.concatenate([elite, children], axis=1)
        fitness[running] = np.concatenate([np.take_along_axis(fitness[running], order, axis=1), child_fitness],
                                          axis=1)
        improved = fitness[running].min(axis=1) < best_fitness[running] - 1e-12
        best_fitness[running] = np.where(improved, fitness[running].min(axis=1), best_fitness[running])
        stall[running] = np.where(improved, 0, stall[running] + 1)
    best = np.argmin(fitness, axis=1)
    return [GeneticResult(population[i, best[i]].copy(), float(fitness[i, best[i]]), int(evaluations[i]),
                          int(generations[i]), population[i], fitness[i]) for i in range(islands)]


def _tournament(fitness: np.ndarray, rng: np.random.Generator, count: int, size: int) -> np.ndarray:
    """``count`` winners per island of tournaments of ``size`` over ``fitness (I, P)``: indices ``(I, count)``."""
    contenders = rng.integers(0, fitness.shape[1], size=(fitness.shape[0], count, size))
    scores = fitness[np.arange(fitness.shape[0])[:, None, None], contenders]
    return np.take_along_axis(contenders, np.argmin(scores, axis=2)[:, :, None], axis=2)[:, :, 0]
