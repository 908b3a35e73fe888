"""Running a simulation: the user's handle (simulation.py) and the observers it runs with:
checkpoints and resume (checkpoint.py), the per-sample divergence check (divergence.py)."""
