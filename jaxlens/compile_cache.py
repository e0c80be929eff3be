"""JAX's persistent compilation cache for the command lines: a second run loads the programs
the first one compiled instead of compiling them again.

Command lines (``python -m jaxlens ...``, ``python -m jaxlens.experiments.classical``,
``.tolerance``) call :func:`enable` before any work: compiled programs are kept in
``JAX_COMPILATION_CACHE_DIR`` when that is set, else in ``$XDG_CACHE_HOME/jaxlens/jax``
(``~/.cache/jaxlens/jax``); ``JAXLENS_COMPILE_CACHE=0`` turns it off. JAX keys each program
by its text, the JAX and XLA versions, the device and the compiler flags, so a cached
program is the one that would be compiled. Functions called from Python are not affected:
the cache is a process-wide setting, left to the caller there.

A program that holds a host callback (an ``eqx.error_if``) is never cached; the analyses
skip re-checks of inputs their entry points checked (``optics.checked_inputs``), so most of
theirs are.
"""

from __future__ import annotations

import os
import warnings

MIN_COMPILE_SECONDS = 0.0
"""Programs that compiled faster are not written (``JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS``
sets another). JAX's default, 1 s, keeps few of a run's programs: a report's figures compile
about 200, most in under a second each."""

OFF = ("0", "false", "no", "off")


def default_dir() -> str:
    """The cache folder used when ``JAX_COMPILATION_CACHE_DIR`` is not set."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(base, "jaxlens", "jax")


def enable(path: str | None = None) -> str | None:
    """Turn JAX's persistent compilation cache on for this process; returns its folder, or
    None when ``JAXLENS_COMPILE_CACHE`` turns it off. ``path`` (a run's own folder) is used
    unless ``JAX_COMPILATION_CACHE_DIR`` names one; by default :func:`default_dir`."""
    if os.environ.get("JAXLENS_COMPILE_CACHE", "").strip().lower() in OFF:
        return None
    import jax

    chosen = os.path.abspath(os.environ.get("JAX_COMPILATION_CACHE_DIR") or path or default_dir())
    try:
        os.makedirs(chosen, exist_ok=True)
    except OSError as e:  # else JAX warns once for every program it tries to read or write
        warnings.warn(f"compile cache off: cannot create {chosen} ({e.strerror}); set "
                      f"JAX_COMPILATION_CACHE_DIR to a writable folder, or "
                      f"JAXLENS_COMPILE_CACHE=0", stacklevel=2)
        return None
    jax.config.update("jax_compilation_cache_dir", chosen)
    if "JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS" not in os.environ:
        jax.config.update("jax_persistent_cache_min_compile_time_secs", MIN_COMPILE_SECONDS)
    return chosen
