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
    integer in ``[0, categories)``.
    """
    population = np.array(initial, dtype=float)
    size, dims = population.shape
    fitness = np.asarray(evaluate(population), dtype=float)
    evaluations = size
    best = int(np.argmin(fitness))
    best_fitness = fitness[best]
    stall = 0
    generation = 0
    for generation in range(1, settings.generations + 1):
        if best_fitness <= target or stall >= settings.stall_generations or should_stop():
            generation -= 1
            break
        order = np.argsort(fitness, kind="stable")
        elite = population[order[: settings.elite]]
        children_count = size - len(elite)
        parents = _tournament(fitness, rng, 2 * children_count, settings.tournament)
        mothers = population[parents[:children_count]]
        fathers = population[parents[children_count:]]
        alpha = 0.3
        u = rng.uniform(-alpha, 1 + alpha, size=(children_count, dims))
        children = mothers + u * (fathers - mothers)
        keep = rng.random(children_count) >= settings.crossover_rate
        children[keep] = mothers[keep]
        mutate = rng.random((children_count, dims)) < settings.mutation_rate
        children += mutate * rng.normal(0.0, settings.mutation_scale, size=(children_count, dims))
        if categories:
            pick = rng.random(children_count) < 0.5
            children[:, 0] = np.where(pick, mothers[:, 0], fathers[:, 0])
            redraw = rng.random(children_count) < settings.mutation_rate
            children[redraw, 0] = rng.integers(0, categories, size=int(redraw.sum()))
        child_fitness = np.asarray(evaluate(children), dtype=float)
        evaluations += children_count
        population = np.concatenate([elite, children])
        fitness = np.concatenate([fitness[order[: settings.elite]], child_fitness])
        best = int(np.argmin(fitness))
        if fitness[best] < best_fitness - 1e-12:
            best_fitness = fitness[best]
            stall = 0
        else:
            stall += 1
    best = int(np.argmin(fitness))
    return GeneticResult(population[best].copy(), float(fitness[best]), evaluations, generation, population, fitness)


def _tournament(fitness: np.ndarray, rng: np.random.Generator, count: int, size: int) -> np.ndarray:
    contenders = rng.integers(0, len(fitness), size=(count, size))
    return contenders[np.arange(count), np.argmin(fitness[contenders], axis=1)]
