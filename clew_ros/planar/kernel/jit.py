"""How every kernel is compiled: numba's options (cached on disk, no GIL, numpy's error model) and the
thread-safe threading layer the parallel kernels need."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numba

if TYPE_CHECKING:
    from numba.core.decorators import _JITWrapper  # in numba's type stubs only


_jit = numba.njit(cache=True, nogil=True, fastmath=False, error_model="numpy")
# Functions that allocate nothing are compiled without reference counting (numba's ``_nrt`` option):
# every array they get is borrowed from the caller, and the atomic increments and decrements numba would
# otherwise emit around each call and view took a tenth of the free intervals' time.
_leaf: _JITWrapper = numba.njit(  # type: ignore[call-overload]  # numba's stubs leave out its underscored options
    cache=True, nogil=True, fastmath=False, error_model="numpy", _nrt=False
)
# The two leaves the hot loops call once per configuration, a free interval and the validity test's first pass, are
# inlined by numba itself (``inline="always"``, before LLVM): called with the packed world (a few named tuples of
# arrays), the free intervals took a twentieth longer, and the straight moves on obstacles_32 too.
_inlined_leaf: _JITWrapper = numba.njit(  # type: ignore[call-overload]  # numba's stubs leave out its underscored options
    cache=True, nogil=True, fastmath=False, error_model="numpy", _nrt=False, inline="always"
)
# Parallel kernels may be launched from several threads at once (several planners in one process):
# only a thread-safe layer (TBB or OpenMP) allows it; without one the kernels run on one thread.
# GNU OpenMP is not fork-safe: start other processes with subprocess (fork + exec) or "spawn".
# (numba.config sets its attributes from the environment at run time: mypy cannot see them.)
if numba.config.THREADING_LAYER == "default":  # type: ignore[attr-defined]
    numba.config.THREADING_LAYER = "threadsafe"  # type: ignore[attr-defined]
