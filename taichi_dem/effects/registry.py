"""``enabled_effects(scene)``: the effect objects a scene calls for, in step order (see the
package docstring)."""
from __future__ import annotations

import importlib

from ..scene.keys import effect_sections
from ..scene.model import Scene
from .base import Effect
from .hertz_mindlin import HertzMindlin
from .rolling import RollingConstantTorque, RollingEPSD


def enabled_effects(scene: Scene) -> tuple[Effect, ...]:
    """The effects this scene calls for, in step order."""
    effects: list[Effect] = [Effect("velocity Verlet for translation and rotation",
                                    "velocity_verlet", "integrate")]
    effects.append(HertzMindlin("Hertz-Mindlin no-slip, tangential history, Coulomb limit"))
    models = {i.rolling_model for i in scene.interactions.values() if i.rolling_friction > 0}
    if "constant_torque" in models:
        effects.append(RollingConstantTorque("rolling friction, constant directional torque"))
    if "epsd" in models:
        effects.append(RollingEPSD("rolling friction, EPSD spring"))
    if scene.walls:
        effects.append(Effect(f"{len(scene.walls)} analytic plane wall(s): the contact law on "
                              "each particle-plane contact", "plane_walls", "detect"))
    if scene.bodies:
        n_tri = sum(len(b.faces) for b in scene.bodies)
        effects.append(Effect(f"{len(scene.bodies)} triangle-mesh bodies ({n_tri} triangles): "
                              "the contact law on each particle-triangle contact, loads on "
                              "each body", "mesh_contact", "detect"))
    # the effects that declare a section (scene/catalog.py), built by the function their
    # section names, imported only for a scene that enables them (a table of their own, or
    # what other sections imply: gravity by [simulation] gravity), in their order of
    # registration
    for path, section in effect_sections().items():
        if path in scene.settings:
            effects.extend(_built(section.builds, scene, scene.settings[path]))
    for f in scene.factories:
        effects.append(Effect(f"factory '{f.name}': {f.material} at "
                              + " then ".join(f"{r * 3.6:g} t/h from {t:g} s"
                                              for t, r in f.mass_rate.points),
                              "factory", "process"))
    if scene.outlets:
        effects.append(Effect("outlets " + ", ".join(o.name for o in scene.outlets)
                              + ": particles removed and accounted", "outlets", "process"))
    for x in scene.sensors:
        effects.append(Effect(f"sensor '{x.name}' ({x.kind})", f"sensor_{x.kind}", "observe"))
    statistics = [x.name for x in scene.sensors if x.kind == "contact_statistics"]
    if statistics:
        # the collisions' impact speeds, counted by the step as each contact begins
        from .impacts import Impacts
        effects.append(Impacts("impact speed of each collision, counted per pair kind",
                               statistics))
    if scene.domain.periodic:
        effects.append(Effect("periodic faces: " + ", ".join(scene.domain.periodic),
                              "periodic", "integrate"))
    if any(f.fixed for f in scene.fills):
        effects.append(Effect("fixed (frozen) particles", "fixed_particles", "integrate"))
    return order_effects(effects)


def _built(builds: str, scene: Scene, settings) -> list:
    """The effect objects the function ``builds`` ("module:function") makes."""
    module, _, function = builds.partition(":")
    return list(getattr(importlib.import_module(module), function)(scene, settings))


def order_effects(effects) -> tuple[Effect, ...]:
    """``effects`` in the order the step runs them: the given order, except that an effect
    comes after every enabled effect its ``after`` names and before every one its ``before``
    names (a stable topological sort; names of effects that are not enabled are ignored).
    A cycle is a programming error in the effects' declarations: ValueError naming it."""
    effects = list(effects)
    names = {e.name for e in effects}
    # edges first -> then, by index in the given order
    index = {}
    for k, e in enumerate(effects):
        index.setdefault(e.name, []).append(k)
    preceding: dict[int, set] = {k: set() for k in range(len(effects))}
    for k, e in enumerate(effects):
        for name in e.after:
            if name in names:
                preceding[k].update(index[name])
        for name in e.before:
            if name in names:
                for j in index[name]:
                    preceding[j].add(k)
    out: list[int] = []
    placed: set = set()
    while len(out) < len(effects):
        ready = [k for k in range(len(effects)) if k not in placed and preceding[k] <= placed]
        if not ready:
            stuck = sorted({effects[k].name for k in range(len(effects)) if k not in placed})
            raise ValueError("the effects' declared order (after/before) has a cycle among: "
                             + ", ".join(stuck))
        out.append(ready[0])           # the earliest in the given order: stable
        placed.add(ready[0])
    return tuple(effects[k] for k in out)


def effect_names(scene: Scene) -> set[str]:
    return {e.name for e in enabled_effects(scene)}
