"""Read a sweep directory and redraw the paper's figures from it: all of it is in sweeps.py,
re-exported here so that `from mjx_curio import analysis` works as before. (Split by job in the
next commit.)"""

from mjx_curio.analysis.sweeps import *  # noqa: F401,F403
from mjx_curio.analysis.sweeps import _quiet_orbax  # noqa: F401  (video.py reads checkpoints with it)
