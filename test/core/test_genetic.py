"""The genetic algorithm improves a known objective, deterministically."""

import numpy as np

from clew_ros.core.genetic import GeneticSettings, minimize, minimize_islands


def sphere(population):
    return np.sum((population - 1.5) ** 2, axis=1)


def test_ga_improves_a_known_objective():
    rng = np.random.default_rng(0)
    initial = rng.uniform(-5, 5, (30, 4))
    result = minimize(sphere, initial, rng, GeneticSettings(population=30, generations=60, stall_generations=60))
    assert result.fitness < 0.05 * sphere(initial).min()
    assert result.fitness == sphere(result.genes[None])[0]


def test_ga_is_deterministic_for_a_seed():
    runs = []
    for _ in range(2):
        rng = np.random.default_rng(42)
        runs.append(minimize(sphere, rng.uniform(-5, 5, (20, 3)), rng, GeneticSettings(generations=10)).genes)
    np.testing.assert_array_equal(runs[0], runs[1])


def test_ga_stops_at_target_and_on_request():
    rng = np.random.default_rng(1)
    result = minimize(sphere, rng.uniform(-5, 5, (20, 2)), rng, GeneticSettings(generations=500), target=1.0)
    assert result.fitness <= 1.0
    assert result.generations < 500
    stopped = minimize(
        sphere, rng.uniform(-5, 5, (20, 2)), rng, GeneticSettings(generations=500), should_stop=lambda: True
    )
    assert stopped.generations == 0


def test_category_gene_stays_in_range():
    rng = np.random.default_rng(2)
    seen = []

    def evaluate(population):
        seen.append(population[:, 0].copy())
        return np.abs(population[:, 0] - 2) + np.sum(population[:, 1:] ** 2, axis=1)

    initial = np.column_stack([rng.integers(0, 4, 16), rng.normal(size=(16, 2))])
    result = minimize(evaluate, initial, rng, GeneticSettings(population=16, generations=20), categories=4)
    values = np.concatenate(seen)
    assert np.all((values >= 0) & (values < 4))
    assert np.all(values == np.round(values))
    assert result.genes[0] == 2


def test_islands_solve_their_own_problems_in_one_batch_and_stop_on_their_own():
    """Three islands, each its own optimum; each evaluate call gets the running islands' individuals
    together; an island that reaches its target stops while the others go on."""
    optima = np.array([[1.0, -2.0], [3.0, 0.5], [-4.0, 4.0]])
    calls = []

    def evaluate(population, islands):
        calls.append(islands.copy())
        return np.sum((population - optima[islands][:, None, :]) ** 2, axis=2)

    rng = np.random.default_rng(3)
    initial = rng.uniform(-5, 5, (3, 24, 2))
    targets = np.array([1e9, -np.inf, -np.inf])  # island 0 is done at once
    settings = GeneticSettings(population=24, generations=40, stall_generations=40)
    results = minimize_islands(evaluate, initial, rng, settings, targets=targets)
    assert results[0].generations == 0
    assert results[1].generations == results[2].generations == 40
    for optimum, result in zip(optima[1:], results[1:], strict=True):
        assert np.linalg.norm(result.genes - optimum) < 0.1
    assert all(list(c) == [1, 2] for c in calls[1:])
    assert list(calls[0]) == [0, 1, 2]


def _reference_ga(evaluate, initial, rng, settings):
    """The plain genetic algorithm as it was before islands (git c57947b, ``genetic.minimize``),
    without target, stop test or categories: the reference for the draws an island makes."""
    population = np.array(initial, dtype=float)
    size, dims = population.shape
    fitness = evaluate(population)
    best_fitness, stall = fitness.min(), 0
    for _ in range(settings.generations):
        if stall >= settings.stall_generations:
            break
        order = np.argsort(fitness, kind="stable")
        elite = population[order[: settings.elite]]
        count = size - len(elite)
        contenders = rng.integers(0, size, size=(2 * count, settings.tournament))
        parents = contenders[np.arange(2 * count), np.argmin(fitness[contenders], axis=1)]
        mothers, fathers = population[parents[:count]], population[parents[count:]]
        children = mothers + rng.uniform(-0.3, 1.3, size=(count, dims)) * (fathers - mothers)
        keep = rng.random(count) >= settings.crossover_rate
        children[keep] = mothers[keep]
        mutate = rng.random((count, dims)) < settings.mutation_rate
        children += mutate * rng.normal(0.0, settings.mutation_scale, size=(count, dims))
        population = np.concatenate([elite, children])
        fitness = np.concatenate([fitness[order[: settings.elite]], evaluate(children)])
        if fitness.min() < best_fitness - 1e-12:
            best_fitness, stall = fitness.min(), 0
        else:
            stall += 1
    return population


def test_one_island_is_the_plain_genetic_algorithm():
    """:func:`minimize` is one island of :func:`minimize_islands`, and draws what the plain GA drew:
    the same seed gives the same individuals as the reference, so single searches plan as before."""
    settings = GeneticSettings(generations=15)
    initial = np.random.default_rng(1).uniform(-5, 5, (20, 3))
    reference = _reference_ga(sphere, initial, np.random.default_rng(9), settings)
    plain = minimize(sphere, initial, np.random.default_rng(9), settings)
    island = minimize_islands(lambda p, _i: sphere(p[0])[None], initial[None], np.random.default_rng(9), settings)
    np.testing.assert_array_equal(plain.population, reference)
    np.testing.assert_array_equal(island[0].population, reference)
