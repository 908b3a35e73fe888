"""The scene: validated plain data (model.py, no Taichi), read from TOML (loader.py) with quantity
strings turned into SI values (units.py)."""
