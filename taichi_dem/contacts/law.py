"""The contact law: the enabled contact effects, composed at compile time, run on one
``Contact`` (contacts/geometry.py) of a given kind.

    response, history = law(contact, history, dt)

Heat effects add conductances (W/K; in parallel, so the heat into i is their sum times
``temperature_difference``); they see every contact handed to the law, touching or within a
margin (``normal_overlap`` < 0). Mechanical effects (Hertz-Mindlin, rolling friction) run in
their tuple's order, only while the contact touches and has a mass to move (``m_eff`` > 0),
each reading what the previous one left in the response (rolling reads the normal force).
"""
import taichi as ti

from .geometry import contact_types

KINDS = ("pair", "plane", "triangle", "surface")


def make_contact_law(effects, kind: str, real, engine):
    """ti.func (contact, history, dt) -> (response, history) for contacts of ``kind``: "pair"
    (two particles), "plane" (an analytic wall), "triangle" (a mesh triangle), "surface"
    (the nearest point of a mesh body, for near-contact heat effects only). ``effects``: the
    scene's enabled effects (effects/); those declaring ``kind`` in their ``kinds`` take part."""
    assert kind in KINDS
    _, Response, _ = contact_types(real)
    def func(e):
        # (an effect whose work differs by contact kind, e.g. counting per kind, is told it)
        return e.contact_func(engine, kind) if e.per_kind else e.contact_func(engine)

    mechanical = tuple(func(e) for e in effects
                       if e.stage == "contact" and kind in e.kinds and e.mechanical)
    heat = tuple(func(e) for e in effects
                 if e.stage == "contact" and kind in e.kinds and not e.mechanical)
    vec0 = ti.Vector([0.0, 0.0, 0.0])

    @ti.func
    def law(c, history, dt):
        out = Response(force=vec0, torque_i=vec0, torque_j=vec0, heat=0.0, conductance=0.0,
                       normal_force=0.0, normal_stiffness=0.0)
        if ti.static(len(heat) > 0):
            if c.conducts != 0:
                for effect in ti.static(heat):
                    out = effect(c, out)
                out.heat = out.conductance * c.temperature_difference
        if ti.static(len(mechanical) > 0):
            if c.normal_overlap > 0.0 and c.m_eff > 0.0:
                for effect in ti.static(mechanical):
                    out, history = effect(c, out, history, dt)
        return out, history

    return law


def has_effects(effects, kind: str) -> bool:
    """Whether any enabled effect acts on contacts of ``kind``."""
    return any(e.stage == "contact" and kind in e.kinds for e in effects)


def margin_fraction(effects, kind: str) -> float:
    """The largest contact margin (a fraction of the particle radius) the enabled effects ask
    for on contacts of ``kind``: pairs that far apart are handed to the law (heat through the
    gas near a contact); 0 when only touching contacts matter."""
    return max([e.margin for e in effects if e.stage == "contact" and kind in e.kinds] + [0.0])
