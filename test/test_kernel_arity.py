"""No function of ``clew_ros`` takes more than :data:`MAX_PARAMETERS` parameters.

Every module of the package is read with :mod:`ast` (nothing is imported, so the compiled kernels are read as
written). A function's parameters are counted as a caller sees them: positional-only, positional and
keyword-only ones (``self`` and ``cls`` included; ``*args`` and ``**kwargs`` not, they name no one value).
What travels together is packed instead: the compiled kernels take the world as named tuples
(:mod:`clew_ros.planar.kernel.packed`, :mod:`clew_ros.spatial.kernels.packed`), the Python functions small
frozen dataclasses (:class:`clew_ros.planar.lattice.LatticeWork`, :class:`clew_ros.planar.regrasp.PlanHints`).
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "clew_ros"
MAX_PARAMETERS = 12

#: Functions allowed over the bar, as ``(module path, function name)``; each names why. An entry that is no
#: longer over the bar fails the test too: the list only shrinks.
EXEMPT: frozenset[tuple[str, str]] = frozenset()


def parameters(function: ast.FunctionDef | ast.AsyncFunctionDef) -> int:
    """``function``'s parameters as a caller sees them (module docstring)."""
    arguments = function.args
    return len(arguments.posonlyargs) + len(arguments.args) + len(arguments.kwonlyargs)


def parameter_counts(root: Path = PACKAGE) -> dict[tuple[str, str, int], int]:
    """Every function (methods and nested ones too) of the modules under ``root``: ``(module path, name, line)``
    to its count of parameters."""
    counts = {}
    for path in sorted(root.rglob("*.py")):
        module = path.relative_to(root.parent).as_posix()
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), filename=str(path))):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                counts[module, node.name, node.lineno] = parameters(node)
    return counts


def test_no_function_takes_more_than_twelve_parameters() -> None:
    counts = parameter_counts()
    assert len(counts) > 1000  # the whole package was read
    over = {key: count for key, count in counts.items() if count > MAX_PARAMETERS}
    unexpected = sorted(
        f"{m}:{line} {name}: {count}" for (m, name, line), count in over.items() if (m, name) not in EXEMPT
    )
    assert not unexpected, f"over {MAX_PARAMETERS} parameters (pack what travels together): {unexpected}"
    stale = EXEMPT - {(m, name) for m, name, _line in over}
    assert not stale, f"no longer over {MAX_PARAMETERS} parameters, remove from EXEMPT: {sorted(stale)}"


def test_the_count_sees_every_kind_of_parameter_and_every_function(tmp_path: Path) -> None:
    # a package written here: positional-only, positional and keyword-only parameters count, star ones do not;
    # methods (self counted), nested and async functions are all found
    package = tmp_path / "pkg"
    (package / "sub").mkdir(parents=True)
    (package / "sub" / "m.py").write_text(
        "def f(a, b, /, c, d=1, *rest, e, f=2, **more):\n"
        "    def inner(x, *, y): pass\n"
        "class C:\n"
        "    async def method(self, p, q): pass\n"
    )
    assert parameter_counts(package) == {
        ("pkg/sub/m.py", "f", 1): 6,
        ("pkg/sub/m.py", "inner", 2): 2,
        ("pkg/sub/m.py", "method", 4): 3,
    }
