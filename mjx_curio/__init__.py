"""mjx_curio: curiosity-driven multi-agent world models on MuJoCo MJX, in pure JAX."""

import os as _os

# XLA's concurrency-optimised CPU scheduler deadlocks vmapped MJX steps over
# many worlds (FACTS.md). The flag must be in place before JAX initialises its
# backend, which happens lazily at the first computation, so importing this
# package first is enough. Flags the user already set are kept.
_FLAG = "--xla_cpu_enable_concurrency_optimized_scheduler=false"
if "xla_cpu_enable_concurrency_optimized_scheduler" not in _os.environ.get("XLA_FLAGS", ""):
    _os.environ["XLA_FLAGS"] = (_os.environ.get("XLA_FLAGS", "") + " " + _FLAG).strip()

__version__ = "0.1.0"
