"""Effects: each physical effect is one module; the stepper composes the ones a scene enables.

``enabled_effects(scene)`` is the tuple the stepper unrolls at compile time (``ti.static``):
an effect not in it is neither allocated, compiled nor run. ``taichi-dem check`` prints it.
"""
from __future__ import annotations

from dataclasses import dataclass

from ..scene.model import Scene


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
            if th.gas_gap:
                effects.append(Effect("gas_gap_wall", "particle",
                                      f"conduction through the gas gap to {', '.join(hot)} "
                                      f"(fluid lens {th.gas_gap_lens:g} R, minimum gap "
                                      f"{th.gas_gap_min_gap:g} m, k_g {th.gap_gas_conductivity:g} "
                                      f"W/(m K); isothermal surfaces)"))
        gas = th.gas
        if gas is not None and not gas.plug_flow:
            effects.append(Effect("convection", "particle",
                                  f"convection to a {gas.model} gas at {gas.temperature:g} K "
                                  f"({gas.correlation})"))
        if gas is not None and gas.plug_flow:
            speed = sum(c * c for c in gas.velocity) ** 0.5
            effects.append(Effect("convection", "particle",
                                  f"convection to the plug-flow gas of the particle's cell "
                                  f"({gas.correlation}, u = {speed:.3g} m/s)"))
            effects.append(Effect("plug_flow_gas", "particle",
                                  f"axial plug-flow gas: {gas.cells} cells over {gas.length:g} m "
                                  f"{gas.flow.replace('_', ' ')}, {gas.mass_flow:g} kg/s in at "
                                  f"{gas.temperature:g} K, energy balance per cell"))
        if th.radiation:
            to = {"gas": "the local gas temperature",
                  "surface": f"'{th.radiation_surface}' at {th.radiation_temperature or 0:g} K",
                  "enclosure": f"an enclosure at {th.radiation_temperature or 0:g} K"}[th.radiation_to]
            where = " inside radiation_region" if th.radiation_region is not None else ""
            effects.append(Effect("radiation", "particle",
                                  f"grey-body radiation to {to}{where} (no shadowing)"))
        if th.moisture:
            effects.append(Effect("drying", "integrate",
                                  f"moisture: evaporation at {th.evaporation_temperature:g} K, "
                                  f"latent heat {th.latent_heat:g} J/kg"))
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
