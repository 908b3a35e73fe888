"""Recorders observe the simulation and write it out; they never change its state."""
