"""Process tooling on the device: outlets that remove particles and the removal log they
write; the drift's hook ``after_drift`` also counts the mass-flow planes' crossings
(sensors/mass_flow.py). The engine's drift calls ``after_drift`` once per moving particle and
step; nothing here is compiled when a scene has no factories, outlets or mass-flow sensors.

A removed particle (outlet or left the domain) is written to the log with what the accounting
needs (id, factory, exit, times, mass, temperature), marked dead and moved to a far-away
``PARKED`` position, so it touches nothing until the next neighbour rebuild drops it (no
rebuild is forced per removal). The log has one entry per particle slot, so it cannot overflow
between two rebuilds; the host drains it at every rebuild and every output sample
(Engine.rebuild, accounting.py), and a log more than half full asks for a rebuild.
"""

import numpy as np
import taichi as ti

from ..engine.regions import region_test
from ..engine.state import PARKED, Flag
from ..sensors.mass_flow import PlaneCrossings

EXIT_LOST = -1          # the particle left the domain

# parked position of dead particles: far outside any domain, but finite in f32 so squared
# distances to it stay finite


class ProcessDevice:
    """Fields and ti.funcs of outlets and the removal log of one engine, and the device
    counters of its mass-flow planes (``planes``, sensors/mass_flow.py)."""

    def __init__(self, engine, tree):
        scene = engine.model.scene
        s = engine.state
        self.outlets = scene.outlets
        self.log_enabled = bool(scene.factories or scene.outlets)
        self.thermal = engine.model.carries("temperature")
        cap = s.capacity
        self.log_capacity = 0
        self.log_temperature = None
        self.log_thermal_mass = None
        self.log_moisture = None
        if self.log_enabled:
            self.log_capacity = cap
            self.log_count = tree.add("log_count", ti.i32, 1)
            self.log_id = tree.add("log_id", ti.i32, cap)
            self.log_origin = tree.add("log_origin", ti.i32, cap)
            self.log_exit = tree.add("log_exit", ti.i32, cap)
            self.log_t_in = tree.add("log_t_in", ti.f64, cap)
            self.log_t_out = tree.add("log_t_out", ti.f64, cap)
            self.log_mass = tree.add("log_mass", ti.f64, cap)
            self.log_temperature = tree.add("log_temperature", ti.f64, cap) if self.thermal else None
            # m c of what leaves (J/K): the enthalpy it carries out, for the energy balance
            self.log_thermal_mass = tree.add("log_thermal_mass", ti.f64, cap) if self.thermal else None
            self.log_moisture = (tree.add("log_moisture", ti.f64, cap)
                                 if engine.model.carries("moisture") else None)
        self.planes = PlaneCrossings(scene, tree)
        if self.log_enabled:
            self._compile_drain(engine)

    # the log's columns, in the order drain() copies them out
    def _log_columns(self):
        cols = [("id", self.log_id), ("origin", self.log_origin), ("exit", self.log_exit),
                ("t_in", self.log_t_in), ("t_out", self.log_t_out), ("mass", self.log_mass)]
        if self.log_temperature is not None:
            cols += [("temperature", self.log_temperature), ("thermal_mass", self.log_thermal_mass)]
        if self.log_moisture is not None:
            cols.append(("moisture", self.log_moisture))
        return cols

    def _compile_drain(self, engine):
        fields = tuple(f for _, f in self._log_columns())

        @ti.kernel
        def copy_log(n: ti.i32, out: ti.types.ndarray(), serial_loops: ti.template()):
            # one launch for every column (ids are exact in f64); a field's to_numpy is one
            # parallel launch each and copies the whole capacity
            ti.loop_config(serialize=serial_loops)
            for q in range(n):
                for c in ti.static(range(len(fields))):
                    out[q, c] = ti.cast(fields[c][q], ti.f64)

        self._copy_log = engine.serial_switch(copy_log)

    def make_funcs(self, engine):
        """Compile-time construction of ``after_drift(i, x_old, x_new, x_wrapped, inside, t)``:
        x_old and x_new are the particle's centre before and after this step's drift (m,
        unwrapped), x_wrapped the new centre wrapped into a periodic domain, inside whether it is
        in the domain, t the time after the step (s); returns True when the particle was
        removed."""
        s = engine.state
        flags = engine.flags
        log_enabled = self.log_enabled
        outlet_tests = [region_test(o.region, engine.values, f"outlet_{k}")
                        for k, o in enumerate(self.outlets)]
        n_outlets = len(outlet_tests)
        thermal = self.thermal
        drying = self.log_moisture is not None
        compensated = engine.model.carries("temperature_residual")
        process_fields = s.process
        count_crossings = self.planes.make_func(s, engine.values)
        me = self

        @ti.func
        def log_removal(i, exit_index, t):
            if ti.static(log_enabled):
                slot = ti.atomic_add(me.log_count[0], 1)
                me.log_exit[slot] = exit_index
                me.log_t_out[slot] = t
                me.log_mass[slot] = ti.cast(s.mass[i], ti.f64)
                if ti.static(process_fields):
                    me.log_id[slot] = s.serial[i]
                    me.log_origin[slot] = s.origin[i]
                    me.log_t_in[slot] = ti.cast(s.birth_time[i], ti.f64)
                else:
                    me.log_id[slot] = s.particle_id[i]
                    me.log_origin[slot] = -1
                    me.log_t_in[slot] = 0.0
                if ti.static(thermal):
                    temperature = ti.cast(s.temperature[i], ti.f64)
                    if ti.static(compensated):
                        temperature += s.temperature_residual[i]
                    me.log_temperature[slot] = temperature
                    me.log_thermal_mass[slot] = 1.0 / ti.cast(s.inverse_thermal_mass[i], ti.f64)
                if ti.static(drying):
                    me.log_moisture[slot] = ti.cast(s.moisture[i], ti.f64)
                if slot * 2 > ti.static(me.log_capacity):
                    flags[Flag.REBUILD] = 1   # rebuild soon: the host drains the log then

        @ti.func
        def after_drift(i, x_old, x_new, x_wrapped, inside, t):
            count_crossings(i, x_old, x_new)
            exit_index = -2
            if not inside:
                exit_index = EXIT_LOST
            else:
                for o in ti.static(range(n_outlets)):
                    if exit_index == -2:
                        if outlet_tests[o](x_wrapped):
                            exit_index = o
            removed = exit_index != -2
            if removed:
                log_removal(i, exit_index, t)
                s.alive[i] = 0
                s.position[i] = ti.Vector([PARKED, PARKED, PARKED])
                s.velocity[i] = ti.Vector([0.0, 0.0, 0.0])
                ti.atomic_add(flags[Flag.DEAD_IN_SLOTS], 1)   # dead, still holding a slot
                if exit_index == EXIT_LOST:
                    ti.atomic_add(flags[Flag.LOST], 1)
            return removed

        return after_drift

    def drain(self):
        """The log's entries since the last drain as numpy arrays (float64 / int), reset."""
        n = int(self.log_count[0])
        if n == 0:
            return None
        columns = self._log_columns()
        table = np.zeros((n, len(columns)), np.float64)
        self._copy_log(n, table)
        out = {}
        for c, (name, field) in enumerate(columns):
            out[name] = (table[:, c].astype(np.int32) if field.dtype == ti.i32
                         else table[:, c].copy())
        self.log_count[0] = 0
        return out
