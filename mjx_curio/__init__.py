"""mjx_curio: curiosity-driven multi-agent world models on MuJoCo MJX, in pure JAX."""

import os as _os

# XLA CPU flags, set before JAX initialises its backend (which happens lazily at the first
# computation, so importing this package first is enough). A flag the user already set wins.
_FLAGS = {
    # The concurrency-optimised scheduler deadlocks vmapped MJX steps over many worlds: a
    # jitted, vmapped mjx.step over 24 worlds hung on its first call with every thread idle.
    "xla_cpu_enable_concurrency_optimized_scheduler": "false",
    # YNNPACK's dot kernels sum in an order that depends on how many threads the device has,
    # so the same runs gave different numbers on one device and on two (forced host devices
    # split the cores). Without them one fewer source of such differences remains (run.py says
    # what still differs between device counts).
    "xla_cpu_experimental_ynn_fusion_type": "",
}
_given = _os.environ.get("XLA_FLAGS", "")
_os.environ["XLA_FLAGS"] = " ".join(
    [_given] + [f"--{k}={v}" for k, v in _FLAGS.items() if f"--{k}=" not in _given]
).strip()

__version__ = "0.1.0"
