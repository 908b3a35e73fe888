"""Heat transfer effects. Each module holds the physics of one effect as Taichi functions the
engine's kernels call when the scene enables the effect (``[thermal]``; see
``taichi_dem.effects.enabled_effects``): a scene without ``[thermal]`` allocates no
temperature and compiles none of this."""
