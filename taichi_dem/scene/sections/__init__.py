"""The scene's own sections (everything but the effects' settings, which live with the
effects): one module per group of sections, each declaring its keys (scene/keys.py) and
reading them. ``scene/loader.py`` mixes them into one parser."""
