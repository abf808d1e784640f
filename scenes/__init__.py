"""The arena's MJCF scenes and wall textures, installed as the package `mjx_curio.scenes`.

The files live in the repository's top-level `scenes/` directory; pyproject.toml maps that
directory to `mjx_curio.scenes`, so an installed package (wheel, `pip install .` or editable)
carries them. Read them with `importlib.resources.files("mjx_curio.scenes")` (as
`mjx_curio.arena.scene_path` does). `make_scenes.py` and `make_textures.py` are the scripts
that wrote the committed XML and PNG files.
"""
