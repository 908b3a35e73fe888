"""Process tooling: factories that insert particles (factories.py), outlets that remove them and
the removal log (outlets.py), and the host-side mass accounting of removals (accounting.py)."""
