"""The device side that advances a simulation: the Taichi runtime (backend.py), the particle and
pair fields (state.py), neighbour search (broadphase.py), the model (model.py), the step itself (stepper.py) and its drivers (drivers.py)."""
