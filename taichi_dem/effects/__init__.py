"""Effects: each physical effect is one module; the stepper composes the ones a scene enables.

``enabled_effects(scene)`` is the tuple the stepper unrolls at compile time (``ti.static``):
an effect not in it is neither allocated, compiled nor run. ``taichi-dem check`` prints it.
"""
from __future__ import annotations

from dataclasses import dataclass

from ..scene import Scene


@dataclass(frozen=True)
class Effect:
    name: str
    stage: str          # "pair" | "particle" | "integrate"
    description: str


def enabled_effects(scene: Scene) -> tuple[Effect, ...]:
    """The effects this scene calls for, in step order."""
    effects = [Effect("velocity_verlet", "integrate",
                      "velocity Verlet for translation and rotation")]
    if any(abs(g) > 0 for g in scene.simulation.gravity):
        effects.append(Effect("gravity", "particle", "uniform gravity"))
    effects.append(Effect("hertz_mindlin", "pair",
                          "Hertz-Mindlin no-slip, tangential history, Coulomb limit"))
    models = {i.rolling_model for i in scene.interactions.values() if i.rolling_friction > 0}
    if "constant_torque" in models:
        effects.append(Effect("rolling_constant_torque", "pair",
                              "rolling friction, constant directional torque"))
    if "epsd" in models:
        effects.append(Effect("rolling_epsd", "pair", "rolling friction, EPSD spring"))
    if scene.walls:
        effects.append(Effect("plane_walls", "particle",
                              f"{len(scene.walls)} analytic plane wall(s)"))
    if scene.bodies:
        n_tri = sum(len(b.faces) for b in scene.bodies)
        effects.append(Effect("mesh_contact", "particle",
                              f"{len(scene.bodies)} triangle-mesh bodies ({n_tri} triangles): "
                              "Hertz-Mindlin with history, loads on each body"))
    if scene.thermal is not None:
        th = scene.thermal
        effects.append(Effect("temperature", "integrate",
                              "explicit temperature update, m c dT/dt = sum Q"))
        if th.conduction:
            effects.append(Effect("conduction", "pair",
                                  f"particle-particle conduction (contact radius correction: "
                                  f"{th.contact_radius_correction})"))
        hot = [w.name for w in list(scene.walls) + list(scene.bodies) if w.temperature is not None]
        if th.wall_conduction and hot:
            effects.append(Effect("wall_conduction", "particle",
                                  "conduction to isothermal " + ", ".join(hot)))
        if th.gas is not None:
            effects.append(Effect("convection", "particle",
                                  f"convection to a {th.gas.model} gas at {th.gas.temperature:g} K "
                                  f"({th.gas.correlation})"))
    for f in scene.factories:
        effects.append(Effect("factory", "process",
                              f"factory '{f.name}': {f.material} at "
                              + " then ".join(f"{r * 3.6:g} t/h from {t:g} s" for t, r in f.mass_rate.points)))
    if scene.outlets:
        effects.append(Effect("outlets", "process",
                              "outlets " + ", ".join(o.name for o in scene.outlets)
                              + ": particles removed and accounted"))
    for x in scene.sensors:
        effects.append(Effect(f"sensor_{x.kind}", "observe", f"sensor '{x.name}' ({x.kind})"))
    if scene.domain.periodic:
        effects.append(Effect("periodic", "integrate",
                              "periodic faces: " + ", ".join(scene.domain.periodic)))
    if any(f.fixed for f in scene.fills):
        effects.append(Effect("fixed_particles", "integrate", "fixed (frozen) particles"))
    return tuple(effects)


def effect_names(scene: Scene) -> set[str]:
    return {e.name for e in enabled_effects(scene)}
