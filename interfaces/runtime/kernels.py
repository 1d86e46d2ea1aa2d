"""The run's compiled (numba) kernels, compiled into the on-disk cache before its clock starts.

Numba compiles a kernel on its first call and keeps the machine code on disk (``cache=True``:
in ``__pycache__`` beside the module, or under ``NUMBA_CACHE_DIR``).  Left to the run, a first
run compiles every kernel inside its first ticks (about a minute on two cores, with the
progress at 0× real time), and every later process still loads each kernel from the cache on
its first call, inside the rate group that makes it (tens of milliseconds: a cycle slip of the
flight software that is none of its doing).

:data:`KERNELS` lists each kernel the runtime calls from Python, with the argument types it
is called with.  :func:`kernels_cached` says whether the cache holds all of them, current for
their source; :func:`compile_kernels` compiles those missing into the cache and loads every
one into the calling process.  The launcher calls it, with a message, before a run whose
kernels are not cached; every process of a run calls it as it starts (then it only loads:
well under a second), so no first call falls inside a tick.
``tests/missions/test_kernel_cache.py`` checks that a run calls the kernels with no other
argument types.
"""

from __future__ import annotations

import importlib
import time
from collections.abc import Callable
from dataclasses import dataclass

from numba import types
from numba.core.dispatcher import Dispatcher

Signature = tuple[types.Type, ...]

F8, I8, BOOL = types.float64, types.int64, types.boolean
V = types.Array(F8, 1, "C")
"""a contiguous float64 vector"""
M = types.Array(F8, 2, "C")
"""a contiguous float64 matrix"""
M_ANY = types.Array(F8, 2, "A")
"""a float64 matrix of any layout (a slice)"""
M_READ = types.Array(F8, 2, "C", readonly=True)
"""a contiguous read-only float64 matrix (a view of a frozen array)"""
T3 = types.Array(F8, 3, "C")
"""a contiguous float64 array of 3 dimensions (a stack of matrices)"""
IV = types.Array(I8, 1, "C")
"""a contiguous int64 vector"""
IM = types.Array(I8, 2, "C")
"""a contiguous int64 matrix"""
BV = types.Array(BOOL, 1, "C")
"""a contiguous boolean vector"""
V_READ = types.Array(F8, 1, "C", readonly=True)
"""a contiguous read-only float64 vector (a message's unpacked array)"""
IV_READ = types.Array(I8, 1, "C", readonly=True)
"""a contiguous read-only int64 vector (a message's unpacked array)"""


@dataclass(frozen=True)
class Kernel:
    """A compiled kernel (``module.name``, a numba dispatcher) and the argument types the
    runtime calls it with."""

    module: str
    name: str
    signatures: tuple[Signature, ...]

    @property
    def label(self) -> str:
        return f"{self.module}.{self.name}"

    def dispatcher(self) -> Dispatcher:
        """The kernel's dispatcher (its module imported)."""
        found = getattr(importlib.import_module(self.module), self.name)
        if not isinstance(found, Dispatcher):
            raise TypeError(f"{self.label} is not a compiled kernel")
        return found

    def loaded(self) -> bool:
        """Whether this process holds the machine code of every signature."""
        disp = self.dispatcher()
        return all(tuple(sig) in disp.overloads for sig in self.signatures)

    def missing(self) -> list[Signature]:
        """The signatures the on-disk cache holds no current machine code for."""
        disp = self.dispatcher()
        cache = disp._cache  # numba's per-function cache: its index names what it holds
        held = cache._cache_file._load_index()  # empty when absent or stale for the source
        codegen = disp.targetctx.codegen()
        return [sig for sig in self.signatures if cache._index_key(sig, codegen) not in held]

    def compile(self) -> None:
        """Compile every signature (from the cache when it holds it) into this process."""
        disp = self.dispatcher()
        for sig in self.signatures:
            disp.compile(sig)


KERNELS: tuple[Kernel, ...] = (
    Kernel("sim.kernels", "attitude_rk4", ((M, T3, T3, M, M, F8, I8),)),
    Kernel("sim.kernels", "relative_rk4", ((M, M_READ, BOOL, F8, BOOL, F8, F8, I8),)),
    Kernel("sim.kernels", "lvlh_attitudes", ((V, M),)),
    Kernel("sim.kernels", "thrust_accel_lvlh", ((M, M, V, M, F8, F8),)),
    Kernel("sim.kernels", "spend_and_hold", ((V, M, V, M, M, V, F8, F8, F8),)),
    Kernel("sim.kernels", "realise_wheel_torque", ((M, M, M, M, V, V, F8),)),
    Kernel("fsw.lib.attitude_kernels", "mekf_propagate", ((V, V, M, V, F8, F8, F8),)),
    Kernel("fsw.lib.attitude_kernels", "mekf_update", ((V, V, M, V, M),)),
    Kernel("fsw.lib.attitude_kernels", "los_eci", ((F8, F8, F8, F8, F8, V, F8, V, V, V, F8),)),
    Kernel("fsw.lib.attitude_kernels", "tracking_torque",
           ((V, V, V, V, V, M, V, F8, F8, F8, F8),)),
    Kernel("fsw.lib.attitude_kernels", "track_cycle",
           ((F8, F8, F8, F8, F8, F8, V, F8, V, V, V, F8, V, V, V, V, M, V, F8, F8, F8, F8,
             F8),)),
    Kernel("fsw.lib.attitude_rows", "_step_rows",
           ((IV, F8, F8, F8, BOOL, M, M, T3, V, BV, V, V, BV, M, M, M, M, M, M, M, V, M, BV, V,
             M, T3, T3, T3, IM, V, M, M, BV, M, V, BV, T3, M, M),)),
    Kernel("gnc.sequential_test", "scan_compiled", ((V, V, V, IV),)),
    Kernel("gnc.interpolate", "columns_at", ((V, V, M, F8), (V, V, M_ANY, F8))),
    Kernel("gnc.infocost_kernels", "_fill",
           tuple((p, M, V, V, V, V, V, V, V, V, BOOL, F8, F8, F8, M) for p in (M, M_ANY))),
    Kernel("ground.fdir.trilateration", "normal_equations_each", ((M_READ, IV, V, IV),)),
    Kernel("gnc.fusion_kernels", "add_checked", ((V, IV_READ, V_READ), (V, IV, V))),
    Kernel("gnc.fusion_kernels", "add_to_rows",
           ((T3, IV, I8, IV_READ, V_READ), (T3, IV, I8, IV, V))),
)


def kernels_cached(kernels: tuple[Kernel, ...] = KERNELS) -> bool:
    """Whether the on-disk cache holds every kernel for every signature, current for its
    source (a kernel whose source changed since it was cached is compiled again)."""
    return not any(k.missing() for k in kernels)


def compile_kernels(progress: Callable[[str], None] | None = None,
                    kernels: tuple[Kernel, ...] = KERNELS, every_s: float = 10.0) -> float:
    """Compile the kernels the cache lacks into it and load every kernel into this process;
    returns the time it took (s, wall).  ``progress``, when given and something is to be
    compiled, is told so first, then every ``every_s`` (s) how far it is, then the time."""
    started = time.perf_counter()
    todo = [k for k in kernels if not k.loaded() and k.missing()]
    tell = progress if todo and progress is not None else _silent
    tell(f"compiling {len(todo)} of the {len(kernels)} numba kernels into the cache (first "
         f"run only, about {COMPILE_S_EACH * len(todo):.0f} s on two cores)...")
    last = started
    for i, kernel in enumerate(kernels, 1):
        kernel.compile()
        if time.perf_counter() - last >= every_s:
            last = time.perf_counter()
            tell(f"... {i} of {len(kernels)} kernels ready ({last - started:.0f} s)")
    spent = time.perf_counter() - started
    tell(f"kernels compiled in {spent:.1f} s")
    return spent


def unlisted_signatures(kernels: tuple[Kernel, ...] = KERNELS) -> dict[str, list[str]]:
    """The argument types this process compiled a kernel of ``kernels``'s modules for that
    :data:`KERNELS` does not list, by kernel (a caller that changed the types it passes: the
    run would compile them inside a tick).  Kernels only other kernels call are not listed:
    they are compiled into their callers."""
    listed = {k.label: set(k.signatures) for k in kernels}
    out: dict[str, list[str]] = {}
    for module in dict.fromkeys(k.module for k in kernels):
        for name, found in vars(importlib.import_module(module)).items():
            if isinstance(found, Dispatcher):
                extra = set(found.signatures) - listed.get(f"{module}.{name}", set())
                if extra:
                    out[f"{module}.{name}"] = sorted(str(sig) for sig in extra)
    return out


COMPILE_S_EACH = 4.0
"""About how long one kernel takes to compile on a two-core machine (s, wall)."""


def _silent(_line: str) -> None:
    """The progress of a compilation nobody watches."""
