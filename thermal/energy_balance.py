"""The particles' energy balance (thermal scenes): where the heat the particles lost went.

    heat out of the particles = E_0 + E_fed - E_removed - E_inside          (J, sum m c T)
                              = heat into isothermal walls and bodies - heat from the gas
                                - heat from the effects' own sources

/series thermal/energy_inside (sum m c T now), energy_fed and energy_removed (carried in by
factories and out through outlets and the domain's faces, since the start), particle_heat_loss
(the first line), wall_heat (the time integral of the walls' and bodies' heat flows) and
gas_heat (the plug-flow gas's integral), J. With [thermal] time_scale = S the integrals are in
thermal time (S x the simulated interval): the particles' temperatures moved S times faster.

Bodies record the mean heat flow over every step of the interval, so their integral is exact;
plane walls record their last step only, so with plane walls the balance closes only to the
change of the wall heat flow within an output interval. The effects' own sources are booked as
each declares (``Effect.energy_terms``: radiation in, the vapour's enthalpy out) into
thermal/source_heat. Convection to a fixed gas is not booked (its source is unbounded), so with
it the two lines differ by it.
"""
from __future__ import annotations


class EnergyBalance:
    def __init__(self, sim):
        self.sim = sim
        self.initial = None          # J, sum m c T at the first sample
        self.wall_heat = 0.0         # J into isothermal walls and bodies so far

    def sample(self, values: dict, now) -> None:
        sim = self.sim
        scene = sim.scene
        scale = scene.settings.get("thermal").time_scale
        inside = float(now.measured["thermal_energy"])
        if self.initial is None:
            self.initial = inside
        for b in scene.bodies:
            key = f"bodies/{b.name}/heat_flow"
            if key in values:
                self.wall_heat += scale * float(values[key]) * now.interval
        for w in scene.walls:
            key = f"walls/{w.name}/heat_flow"
            if key in values:
                self.wall_heat += scale * float(values[key]) * now.interval
        fed = sim.factories.inserted_energy if sim.factories is not None else 0.0
        removed = sim.accounts.removed_energy if sim.accounts is not None else 0.0
        gas = float(values.get("gas/transferred_heat", 0.0))
        # the effects' own sources (radiation, the vapour): each declares its series
        source = sum(sign * float(values[key]) for effect in sim.engine.model.effect_list
                     for key, sign in effect.energy_terms.items() if key in values)
        values["thermal/energy_inside"] = inside
        values["thermal/energy_fed"] = fed
        values["thermal/energy_removed"] = removed
        values["thermal/particle_heat_loss"] = self.initial + fed - removed - inside
        values["thermal/wall_heat"] = self.wall_heat
        values["thermal/gas_heat"] = gas
        values["thermal/source_heat"] = source

    def state_dict(self) -> dict:
        return {"initial": self.initial if self.initial is not None else float("nan"),
                "wall_heat": self.wall_heat}

    def load_state_dict(self, d: dict):
        import math
        initial = float(d["initial"])
        self.initial = None if math.isnan(initial) else initial
        self.wall_heat = float(d["wall_heat"])
