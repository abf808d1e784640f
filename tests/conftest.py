"""Shared pytest setup."""

import os

# MuJoCo chooses its OpenGL backend when `mujoco` is first imported, by whichever test module
# imports it first; tests/test_render.py compares against MuJoCo's off-screen renderer, which
# on a headless machine needs OSMesa (apt-get install -y libosmesa6).
os.environ.setdefault("MUJOCO_GL", "osmesa")
