"""The genetic algorithm improves a known objective, deterministically."""

import numpy as np

from clew_ros.core.genetic import GeneticSettings, minimize


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
    assert result.fitness <= 1.0 and result.generations < 500
    stopped = minimize(sphere, rng.uniform(-5, 5, (20, 2)), rng, GeneticSettings(generations=500),
                       should_stop=lambda: True)
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
    assert np.all((values >= 0) & (values < 4)) and np.all(values == np.round(values))
    assert result.genes[0] == 2
