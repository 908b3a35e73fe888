"""Rigid triangle-mesh bodies, device side: triangle binning, particle-triangle contact lists
with history, and the loads (force, torque about the axis point) summed from contacts.

The bodies' motion comes from the host (kinematics.py: :class:`BodyKinematics`). Here
(:class:`MeshContacts`): reference triangles (their vertices at t = 0) and one frame (rotation,
offset) per body, computed on the device from the schedules each step, so the triangles
themselves never need rewriting; triangles binned into the cell grid (re-binned when a body has
moved half the skin); per particle a list of candidate triangles within r + skin (rebuilt with
the particle neighbour list), carrying the contact history by triangle id.

De-duplication (PHYSICS.md: one contact per flat or convex surface): a particle's overlapping
triangles of one body are taken deepest first; a further one is dropped when its normal is
within 30 degrees of an accepted one or its closest point does not lie in front of the
accepted contact's plane (a neighbouring triangle of the same flat or convex surface,
touched at its edge or vertex). A concave corner (a flight meeting the shell) keeps both
faces. When a contact moves on to a neighbouring triangle, it takes the history (every
value, contacts/history.py) of the contact it replaces.

The bodies' triangles, frames and loads are frames.py's.
"""

import math

import numpy as np
import taichi as ti

from .surface_survey import SurfaceSurvey
from ..contacts.geometry import contact_types
from ..contacts.history import history_members, make_history_io
from ..contacts.law import has_effects, margin_fraction
from ..effects.mesh_contact import closest_point_on_triangle
from ..setup.tuning import LIST_GROWTH
from ..setup.timestep import SKIN_MAX_DIAMETERS
from ..engine.broadphase import exclusive_scan, previous_entry
from ..engine import transfer
from ..setup.memory import bucket
from ..engine.values import reader
from .triangle_images import make_triangle_image
from ..engine.state import fit_rows, grown_capacity
from .frames import BodyFrames, BodyLoads, BodyTriangles
from .kinematics import BodyKinematics

SAME_SURFACE_COS = math.cos(math.radians(30.0))
# the stored names of the history values per mesh contact (checkpoints know them)
MESH_HISTORY_NAMES = {"tangential_history": "mesh_history",
                      "rolling_history": "mesh_rolling_history"}


@ti.data_oriented
class MeshContacts:
    """Device state and kernels of the particle-triangle contacts of one simulation.

    The bodies' triangles, frames and loads are its parts (frames.py). Why it still holds
    46 attributes, over the 40 of docs/architecture.md: the triangle bins (their counts,
    starts, fill and items, and the items' capacity), the candidate rows per particle (start,
    count and the previous rebuild's by particle id), the candidate entries with their
    history and the previous list's (the carried history is matched by triangle id), and the
    scratch of the candidate search are grown and reallocated together by one rebuild
    (``rebuild_rows``; checkpoints restore their sizes: run/checkpoint.py) and read together
    by the fused rebuild (engine/broadphase.py)."""

    def __init__(self, engine, kinematics: BodyKinematics):
        self.e = engine
        # what touches the bodies now, for the sensors and the checks (surface_survey.py)
        self.survey = SurfaceSurvey(self)
        bodies = kinematics.bodies
        real = engine.model.real
        s = engine.state
        t = self.tree = engine.new_tree()
        ncell = engine.model.grid.cell_capacity
        self.triangles = BodyTriangles(t, bodies, real)
        self.n_triangles = self.triangles.count
        self.n_bodies = len(bodies)
        # each body's frame now (x_world = R (x_ref - axis_point) + axis_point + offset) and
        # the loads its contacts sum (frames.py)
        self.frames = BodyFrames(t, kinematics, real, engine.model.tables.index,
                                 engine.model.heats_walls)
        self.tri_cell_count = t.add("tri_cell_count", ti.i32, ncell)
        self.tri_cell_start = t.add("tri_cell_start", ti.i32, ncell + 1)
        self.tri_cell_fill = t.add("tri_cell_fill", ti.i32, ncell)
        self.loads = BodyLoads(t, real, self.n_bodies, s.capacity, engine.model.heats_walls)
        self.mesh_start = t.add("mesh_start", ti.i32, s.capacity + 1)
        self.mesh_count = t.add("mesh_count", ti.i32, s.capacity)
        self.old_start_by_id = t.add("old_mesh_start_by_id", ti.i32, s.capacity)
        self.old_count_by_id = t.add("old_mesh_count_by_id", ti.i32, s.capacity)
        t.finalize()
        # the triangles and the frames: one copy kernel for both
        transfer.write(self.triangles.writes() + self.frames.writes())
        self.items_tree = None
        self.entries_tree = None
        self.scratch_tree = None
        # gas-gap conduction reaches a fluid lens beyond the contact (thermal/gas_gap.py)
        self.lens = margin_fraction(engine.model.contact_effects, "surface")
        self.expand = engine.model.max_radius * (1.0 + self.lens) + engine.model.skin
        # room for the triangles binned into the cells of any skin (the skin follows dt: a
        # smaller one made more, smaller cells and more items, which grew the list and
        # compiled the binning and the rows again at the first rebuild)
        self._alloc_items(bucket(max(4 * self.n_triangles, 1024,
                                     int(self._items_bound() * LIST_GROWTH) + 16)))
        self._alloc_scratch(16)
        # one candidate entry per slot to start with (~300 bytes each in f64, setup/memory.py):
        # the seed's cooler slice at 60 kg/m needs ~0.5 per sphere once the bed has packed, and
        # a list that grows mid-run compiles the step's kernels again (a quarter per slot grew
        # at 0.11 s)
        self._alloc_entries(bucket(max(s.capacity, 1024)))
        self.minimum_image = engine.model.grid.make_minimum_image()
        self.triangle_image = make_triangle_image(engine.model.grid, self.expand)
        self.binned_time = 0.0
        self.interval_steps = 0
        # the ti.func bodies of the kernels (Broadphase.fused_rebuild runs them in one launch)
        self.bodies = {}
        self._compile_static_kernels()

    def _np_real(self):
        return np.float64 if self.e.model.real == ti.f64 else np.float32

    def upload_schedules(self):
        """The bodies' speed schedules again (frames.py)."""
        self.frames.upload_schedules()

    # --------------------------------------------------------------- allocation
    def _items_bound(self) -> int:
        """The (triangle, cell) items of the triangles where they start, binned by their boxes
        grown by the reach of the largest automatic skin (m), in cells of the smallest cutoff
        (GridSpec.least_cutoff) wherever they fall: what the binning counts at any skin the
        time step sets, or more (it also drops cells far from a triangle's plane). It does not
        depend on dt nor, but for a triangle wider than the domain, on the domain."""
        g = self.e.model.grid
        if not self.n_triangles:
            return 0
        radius = self.e.model.max_radius
        reach = max(radius * (1.0 + self.lens) + SKIN_MAX_DIAMETERS * 2.0 * radius, self.expand)
        tris = self.triangles._tris
        extent = tris.max(axis=1) - tris.min(axis=1) + 2.0 * reach
        per_axis = np.minimum(np.ceil(extent / g.least_cutoff) + 1,
                              np.ceil(np.asarray(g.span) / g.least_cutoff) + 1)
        return int(np.prod(per_axis, axis=1).sum())

    def _alloc_items(self, capacity):
        if self.items_tree is not None:
            self.items_tree.destroy()
        self.items_capacity = capacity
        t = self.items_tree = self.e.new_tree()
        self.tri_cell_items = t.add("tri_cell_items", ti.i32, capacity)
        t.finalize()

    def _alloc_scratch(self, width):
        if self.scratch_tree is not None:
            self.scratch_tree.destroy()
        self.scratch_width = width
        t = self.scratch_tree = self.e.new_tree()
        self.scratch = t.add("mesh_scratch", ti.i32, (self.e.state.capacity, width))
        t.finalize()

    def _alloc_entries(self, capacity, keep_old=None):
        saved = None
        if self.entries_tree is not None:
            # the previous list, by triangle id, and every history value it carries
            names = ["old_tri", "old_contact"] + [f"old_{n}" for n in self.history_names]
            saved = dict(zip(names, transfer.read([self.old_fields()[n] for n in names])))
            self.entries_tree.destroy()
        self.entries_capacity = capacity
        real = self.e.model.real
        t = self.entries_tree = self.e.new_tree()
        self.mesh_tri = t.add("mesh_tri", ti.i32, capacity)
        self.mesh_contact = t.add("mesh_contact", ti.u8, capacity)
        self.mesh_status = t.add("mesh_status", ti.u8, capacity)
        self.mesh_overlap = t.add("mesh_overlap", real, capacity)
        self.mesh_normal = t.add("mesh_normal", real, capacity, vector=True)
        self.mesh_point = t.add("mesh_point", real, capacity, vector=True)
        self.old_tri = t.add("old_mesh_tri", ti.i32, capacity)
        self.old_contact = t.add("old_mesh_contact", ti.u8, capacity)
        # each candidate placed once per step (make_place_candidates), before the pair stage:
        # its triangle in the world frame now (vertex a, edges e1 = b - a, e2 = c - a; m) and
        # the particle's periodic image nearest it (m); scratch, remade every step
        self.candidate_a = t.add("candidate_a", real, capacity, vector=True, scratch=True)
        self.candidate_e1 = t.add("candidate_e1", real, capacity, vector=True, scratch=True)
        self.candidate_e2 = t.add("candidate_e2", real, capacity, vector=True, scratch=True)
        self.candidate_image = t.add("candidate_image", real, capacity, vector=True,
                                     scratch=True)
        # and what the shields test first: e1 x e2 (m^2) and that image's side of the plane,
        # (image - a) . (e1 x e2) (m^3)
        self.candidate_normal = t.add("candidate_normal", real, capacity, vector=True,
                                      scratch=True)
        self.candidate_side = t.add("candidate_side", real, capacity, scratch=True)
        # the history values the enabled effects keep (contact_fields), per mesh contact and
        # for the previous list, under the names checkpoints know (mesh_history: the
        # tangential spring; mesh_rolling_history: EPSD's)
        self.history, self.old_history_by_name = {}, {}
        for name, (vec, kind) in self.e.model.contact_fields.items():
            stored = MESH_HISTORY_NAMES.get(name, "mesh_" + name)
            self.history[name] = t.add(stored, real, capacity, vector=vec)
            self.old_history_by_name[name] = t.add("old_" + stored, real, capacity, vector=vec)
        t.finalize()
        if saved is not None:
            fields = self.old_fields()
            transfer.write([(fields[n], fit_rows(v, capacity)) for n, v in saved.items()])

    @property
    def history_names(self) -> list:
        return list(self.history)

    def old_fields(self) -> dict:
        """The previous list's fields by name: old_tri, old_contact, old_<history value>."""
        out = {"old_tri": self.old_tri, "old_contact": self.old_contact}
        out.update({f"old_{n}": f for n, f in self.old_history_by_name.items()})
        return out

    # --------------------------------------------------------------- kernels
    def _compile_static_kernels(self):
        self.frames.compile()
        flush_loads_body = self.loads.make_flush()

        @ti.kernel
        def flush_loads(n: ti.i32, serial_loops: ti.template()):
            flush_loads_body(n, serial_loops)

        self._flush_loads = self.e.serial_switch(flush_loads)
        self.bodies["flush_loads"] = flush_loads_body
        self._compile_binning()
        self._compile_rows()

    @ti.func

    @ti.func
    def world_triangle(self, t):
        b = self.triangles.tri_body[t]
        rot = self.frames.rotation[b]
        p = self.frames.axis_point[b]
        shift = p + self.frames.offset[b]
        return (rot @ (self.triangles.tri_a[t] - p) + shift, rot @ (self.triangles.tri_b[t] - p) + shift,
                rot @ (self.triangles.tri_c[t] - p) + shift)

    def _compile_binning(self):
        m = self
        g = self.e.model.grid
        lo_of, _, _, inv_cell_of, dims_of, n_cells_of = g.layout_funcs()
        cell_of_size = reader(g.values, "cell_size", tuple(g.cell_size))
        # the triangles' count read at run time (their arrays have bucketed slots)
        count_of = reader(g.values, "triangle_count", self.n_triangles, integer=True)
        expand_of = reader(g.values, "triangle_reach", self.expand)
        half_diagonal_of = reader(g.values, "half_cell_diagonal",
                                        0.5 * float(np.linalg.norm(g.cell_size)))
        items = self.tri_cell_items

        @ti.func
        def visit_cells(t, fill: ti.template()):
            a, b, c = m.world_triangle(t)
            lo, inv_cell, cell, dims = lo_of(), inv_cell_of(), cell_of_size(), dims_of()
            expand, half_diagonal = expand_of(), half_diagonal_of()
            normal = (b - a).cross(c - a).normalized()
            lo_c = ti.cast(ti.floor((ti.min(a, b, c) - expand - lo) * inv_cell), ti.i32)
            hi_c = ti.cast(ti.floor((ti.max(a, b, c) + expand - lo) * inv_cell), ti.i32)
            for k in ti.static(range(3)):
                if ti.static(g.periodic[k]):
                    # across a periodic face the cells wrap; never visit one twice
                    if hi_c[k] - lo_c[k] + 1 > dims[k]:
                        lo_c[k] = 0
                        hi_c[k] = dims[k] - 1
                else:
                    lo_c[k] = ti.max(ti.min(lo_c[k], dims[k] - 1), 0)
                    hi_c[k] = ti.max(ti.min(hi_c[k], dims[k] - 1), 0)
            for cx in range(lo_c[0], hi_c[0] + 1):
                for cy in range(lo_c[1], hi_c[1] + 1):
                    for cz in range(lo_c[2], hi_c[2] + 1):
                        centre = lo + (ti.Vector([cx, cy, cz]) + 0.5) * cell
                        # a cell far from the triangle's plane cannot hold a particle near it
                        if ti.abs((centre - a).dot(normal)) <= half_diagonal + expand:
                            w = ti.Vector([cx, cy, cz])
                            for k in ti.static(range(3)):
                                if ti.static(g.periodic[k]):
                                    w[k] = (w[k] % dims[k] + dims[k]) % dims[k]
                            cid = (w[0] * dims[1] + w[1]) * dims[2] + w[2]
                            if ti.static(fill):
                                slot = m.tri_cell_start[cid] + ti.atomic_add(m.tri_cell_fill[cid], 1)
                                items[slot] = t
                            else:
                                ti.atomic_add(m.tri_cell_count[cid], 1)

        @ti.func
        def count_bins_body(serial_loops: ti.template()):
            ti.loop_config(serialize=serial_loops)
            for c in range(n_cells_of()):
                m.tri_cell_count[c] = 0
                m.tri_cell_fill[c] = 0
            ti.loop_config(serialize=serial_loops)
            for t in range(count_of()):
                visit_cells(t, False)
            n_cells = n_cells_of()
            exclusive_scan(m.tri_cell_count, m.tri_cell_start, n_cells)
            return m.tri_cell_start[n_cells]

        @ti.kernel
        def count_bins(serial_loops: ti.template()) -> ti.i32:
            return count_bins_body(serial_loops)

        @ti.func
        def fill_bins_body(serial_loops: ti.template()):
            ti.loop_config(serialize=serial_loops)
            for t in range(count_of()):
                visit_cells(t, True)

        @ti.kernel
        def fill_bins(serial_loops: ti.template()):
            fill_bins_body(serial_loops)

        self._count_bins = self.e.serial_switch(count_bins)
        self._fill_bins = self.e.serial_switch(fill_bins)
        self.bodies.update(count_bins=count_bins_body, fill_bins=fill_bins_body)
        self.e.broadphase.drop_fused_rebuild()

    def _compile_rows(self):
        m = self
        s = self.e.state
        carried = [(self.history[n], self.old_history_by_name[n]) for n in self.history]
        skin_of = self.e.skin_of
        lens = self.lens
        width = self.scratch_width
        scratch = self.scratch

        @ti.func
        def save_rows_body(n, serial_loops: ti.template()):
            ti.loop_config(serialize=serial_loops)
            for i in range(n):
                pid = s.particle_id[i]
                m.old_start_by_id[pid] = m.mesh_start[i]
                m.old_count_by_id[pid] = m.mesh_count[i]
                for k in range(m.mesh_start[i], m.mesh_start[i] + m.mesh_count[i]):
                    m.old_tri[k] = m.mesh_tri[k]
                    m.old_contact[k] = m.mesh_contact[k]
                    for value, old_value in ti.static(carried):
                        old_value[k] = value[k]

        @ti.kernel
        def save_rows(n: ti.i32, serial_loops: ti.template()):
            save_rows_body(n, serial_loops)

        @ti.func
        def find_candidates_body(n, serial_loops: ti.template()):
            ti.loop_config(serialize=serial_loops)
            for i in range(n):
                c = s.cell[i]
                xi = s.position[i]
                reach = s.radius[i] * ti.static(1.0 + lens) + skin_of()
                count = 0
                for slot in range(m.tri_cell_start[c], m.tri_cell_start[c + 1]):
                    t = m.tri_cell_items[slot]
                    a, b, cc = m.world_triangle(t)
                    x_image = m.triangle_image(xi, a, b, cc)
                    q, region = closest_point_on_triangle(x_image, a, b, cc)
                    d = x_image - q
                    if d.dot(d) < reach * reach:
                        if count < width:
                            scratch[i, count] = t
                        count += 1
                m.mesh_count[i] = count
            longest = 0
            ti.loop_config(serialize=serial_loops)
            for i in range(n):
                ti.atomic_max(longest, m.mesh_count[i])
            exclusive_scan(m.mesh_count, m.mesh_start, n)
            return longest

        @ti.kernel
        def find_candidates(n: ti.i32, serial_loops: ti.template()) -> ti.i32:
            return find_candidates_body(n, serial_loops)

        self._save_rows = self.e.serial_switch(save_rows)
        self._find_candidates = self.e.serial_switch(find_candidates)
        self.bodies.update(save_rows=save_rows_body, find_candidates=find_candidates_body)
        self.e.broadphase.drop_fused_rebuild()
        self._compile_compact()

    def _compile_compact(self):
        m = self
        s = self.e.state
        scratch = self.scratch
        # (value, its previous list's field, its zero)
        carried = [(self.history[n], self.old_history_by_name[n],
                    ti.Vector([0.0, 0.0, 0.0]) if self.e.model.contact_fields[n][0] else 0.0)
                   for n in self.history]

        @ti.func
        def compact_and_carry_body(n, serial_loops: ti.template()):
            ti.loop_config(serialize=serial_loops)
            for i in range(n):
                pid = s.particle_id[i]
                old_start = m.old_start_by_id[pid]
                old_count = m.old_count_by_id[pid]
                for c in range(m.mesh_count[i]):
                    k = m.mesh_start[i] + c
                    t = scratch[i, c]
                    m.mesh_tri[k] = t
                    old = previous_entry(m.old_tri, old_start, old_count, t)
                    m.mesh_contact[k] = ti.u8(0)
                    for value, old_value, zero in ti.static(carried):
                        value[k] = zero
                    if old >= 0:
                        m.mesh_contact[k] = m.old_contact[old]
                        for value, old_value, zero in ti.static(carried):
                            value[k] = old_value[old]

        @ti.kernel
        def compact_and_carry(n: ti.i32, serial_loops: ti.template()):
            compact_and_carry_body(n, serial_loops)

        self._compact_and_carry = self.e.serial_switch(compact_and_carry)
        self.bodies["compact_and_carry"] = compact_and_carry_body
        self.e.broadphase.drop_fused_rebuild()

    # --------------------------------------------------------------- contact law
    def make_select_contacts(self):
        """ti.func (start, end, radius): among the candidate entries start .. end - 1 that
        touch (status 0), accept the deepest (status 1) and drop (status 2) the others of
        the same body that lie on the same flat or convex surface (normals within
        SAME_SURFACE_COS, or not in front of it): one contact per surface, however it is
        cut into triangles."""
        m = self
        same_surface_cos = SAME_SURFACE_COS

        @ti.func
        def select_contacts(start, end, ri):
            for _ in range(end - start):
                best = -1
                best_overlap = 0.0
                for k in range(start, end):
                    if m.mesh_status[k] == 0 and m.mesh_overlap[k] > best_overlap:
                        best = k
                        best_overlap = m.mesh_overlap[k]
                if best < 0:
                    break
                m.mesh_status[best] = ti.u8(1)
                body = m.triangles.tri_body[m.mesh_tri[best]]
                n_best = m.mesh_normal[best]
                for k in range(start, end):
                    if m.mesh_status[k] == 0 and m.triangles.tri_body[m.mesh_tri[k]] == body:
                        in_front = (m.mesh_point[k] - m.mesh_point[best]).dot(n_best)
                        if m.mesh_normal[k].dot(n_best) > same_surface_cos or in_front <= 1e-3 * ri:
                            m.mesh_status[k] = ti.u8(2)

        return select_contacts

    def make_particle_contacts(self, triangle_law, surface_law, sphere_surface):
        """ti.func (i, position, velocity, angular velocity, radius, mass, inverse mass,
        inverse inertia, acceleration, material, temperature, dt) -> (force N, torque N m,
        heat W, conductance W/K) of all mesh contacts of particle i; adds the reactions to the
        bodies' load sums. Detection is here (candidates, closest points, one contact per flat
        or convex surface); the physics is the contact law (contacts/law.py) on each accepted
        contact (``triangle_law``) and, for near-contact heat effects, on each body's surface
        point nearest the centre (``surface_law``)."""
        m = self
        e = self.e
        real = e.model.real
        # the history values the enabled effects keep (contacts/history.py), stored per mesh
        # contact under the names checkpoints know: mesh_history (the tangential spring),
        # mesh_rolling_history (EPSD's)
        members = history_members(e.model.effect_list)
        _, _, History = contact_types(real, members)
        mesh_history = make_history_io(History, members,
                                       {k: m.history[k + "_history"] for k in members})
        periodic = any(e.model.grid.periodic)
        heat_loads = self.loads.particle_load_heat is not None
        # near-contact heat effects (the gas gap) see each body's nearest surface point within
        # the margin they ask for (one lens per body: the plane closed form stands for the
        # surface there)
        near = has_effects(e.model.contact_effects, "surface")
        lens = self.lens
        nb = self.n_bodies
        vec0 = ti.Vector([0.0, 0.0, 0.0])
        split = e.model.split_positions
        select_contacts = self.make_select_contacts()

        @ti.func
        def particle_contacts(i, xi, vi, wi, ri, mass_i, inv_mi, inverse_inertia_i, ai, mi,
                              temperature_i, dt):
            force = vec0
            torque = vec0
            heat = 0.0
            conductance = 0.0
            start = m.mesh_start[i]
            end = start + m.mesh_count[i]
            residual_i = vec0
            if ti.static(split):
                residual_i = e.state.position_residual[i]
            nearest = ti.Vector([ri * ti.static(2.0 + lens)] * max(nb, 1))
            # geometry of every candidate triangle, in its body's reference frame: the particle
            # is moved into that frame (one rotation) instead of the triangle out of it (three)
            for k in range(start, end):
                t = m.mesh_tri[k]
                body = m.triangles.tri_body[t]
                rot = m.frames.rotation[body]
                pivot = m.frames.axis_point[body]
                x_world = xi
                if ti.static(periodic):
                    # the particle's image nearest the whole triangle (a triangle longer than
                    # half the period is nearer another image than the one near its vertex),
                    # found this step before the pair stage (make_place_candidates)
                    x_world = m.candidate_image[k]
                m.mesh_status[k] = ti.u8(2)
                # the particle and the triangle relative to the body's pivot: with split
                # positions (f32 far from the origin, engine/precision.py) the differences of
                # near coordinates are exact and the residual is added to them
                x_ref = rot.transpose() @ (x_world - pivot - m.frames.offset[body])
                if ti.static(split):
                    x_ref += rot.transpose() @ residual_i
                tri_a = m.triangles.tri_a[t] - pivot
                # a triangle whose plane is farther than r (and the lens) cannot touch (most
                # candidates)
                if ti.abs((x_ref - tri_a).dot(m.triangles.tri_normal[t])) < ri * ti.static(1.0 + lens):
                    q, region = closest_point_on_triangle(x_ref, tri_a, m.triangles.tri_b[t] - pivot,
                                                          m.triangles.tri_c[t] - pivot)
                    d = x_ref - q
                    dist_sq = d.dot(d)
                    if ti.static(near):
                        for bb in ti.static(range(nb)):
                            if body == bb:
                                if dist_sq < nearest[bb] * nearest[bb] and dist_sq > 0.0:
                                    nearest[bb] = ti.sqrt(dist_sq)
                    if dist_sq < ri * ri and dist_sq > 0.0:
                        dist = ti.sqrt(dist_sq)
                        m.mesh_overlap[k] = ri - dist
                        m.mesh_normal[k] = rot @ (d / dist)
                        m.mesh_point[k] = rot @ q + pivot + m.frames.offset[body]
                        m.mesh_status[k] = ti.u8(0)
            # deepest first; drop neighbours of the same flat or convex surface
            select_contacts(start, end, ri)
            # the contact law on each accepted contact
            for k in range(start, end):
                if m.mesh_status[k] == 1:
                    body = m.triangles.tri_body[m.mesh_tri[k]]
                    history = mesh_history.load(k)
                    if m.mesh_contact[k] == 0:
                        # a contact moving on to a neighbouring triangle keeps its history
                        for o in range(start, end):
                            if (o != k and m.mesh_contact[o] != 0 and m.mesh_status[o] != 1
                                    and m.triangles.tri_body[m.mesh_tri[o]] == body):
                                history = mesh_history.take(k, o)
                                m.mesh_contact[o] = ti.u8(0)
                                break
                    normal = m.mesh_normal[k]
                    overlap = m.mesh_overlap[k]
                    # the overlap centre, in the triangle's frame (periodic image of the particle)
                    contact_point = m.mesh_point[k] - 0.5 * overlap * normal
                    lever_body = contact_point - (m.frames.axis_point[body] + m.frames.offset[body])
                    wall_velocity = m.frames.body_velocity[body] + m.frames.angular_velocity[body].cross(lever_body)
                    body_temperature = m.frames.body_temperature[body]
                    c = sphere_surface(normal, overlap, ri, vi, wi, ai, mass_i, inv_mi,
                                       inverse_inertia_i, mi, m.frames.body_material[body],
                                       wall_velocity, m.frames.angular_velocity[body],
                                       body_temperature - temperature_i,
                                       1 if body_temperature >= 0.0 else 0)
                    c.particle = i
                    out, history = triangle_law(c, history, dt)
                    if ti.static(heat_loads):
                        heat += out.heat
                        conductance += out.conductance
                        m.loads.particle_load_heat[i, body] = m.loads.particle_load_heat[i, body] - out.heat
                    force += out.force
                    torque += out.torque_i
                    m.loads.particle_load_force[i, body] = m.loads.particle_load_force[i, body] - out.force
                    # about the body's axis: the reaction at the contact point, plus the
                    # rolling resistance's reaction
                    m.loads.particle_load_torque[i, body] = (m.loads.particle_load_torque[i, body]
                                                       - lever_body.cross(out.force) + out.torque_j)
                    mesh_history.store(k, history)
                    m.mesh_contact[k] = ti.u8(1)
                elif m.mesh_contact[k] != 0:
                    m.mesh_contact[k] = ti.u8(0)
                    mesh_history.clear(k)
            if ti.static(near):
                # near-contact heat: the law on each body's nearest surface point
                for bb in ti.static(range(nb)):
                    body_temperature = m.frames.body_temperature[bb]
                    if body_temperature >= 0.0 and nearest[bb] < ri * ti.static(1.0 + lens):
                        c = sphere_surface(vec0, ri - nearest[bb], ri, vi, wi, ai, mass_i,
                                           inv_mi, inverse_inertia_i, mi, m.frames.body_material[bb],
                                           vec0, vec0, body_temperature - temperature_i, 1)
                        c.particle = i
                        out, _ = surface_law(c, mesh_history.empty(), dt)
                        heat += out.heat
                        conductance += out.conductance
                        m.loads.particle_load_heat[i, bb] = m.loads.particle_load_heat[i, bb] - out.heat
            return force, torque, heat, conductance

        return particle_contacts

    def make_place_candidates(self):
        """ti.func place_candidates(i): particle i's candidate triangles in the world frame now
        and its periodic image nearest each (candidate_a, candidate_e1, candidate_e2,
        candidate_image). Run for every particle once per step, after the bodies' frames are
        set and before the pair stage: the shields of every pair near a body (make_shields)
        and the particle's own mesh contacts in the gather read them, where each placed the
        triangle again (the shields per pair and candidate: 22 % of a flighted drum's step,
        19 % of the seed's cooler slice; BENCHMARKS "The shields")."""
        m = self

        @ti.func
        def place_candidates(i):
            x = m.e.state.position[i]
            for k in range(m.mesh_start[i], m.mesh_start[i] + m.mesh_count[i]):
                wa, wb, wc = m.world_triangle(m.mesh_tri[k])
                e1 = wb - wa
                e2 = wc - wa
                normal = e1.cross(e2)
                # (x itself without periodic axes)
                image = m.triangle_image(x, wa, wb, wc)
                m.candidate_a[k] = wa
                m.candidate_e1[k] = e1
                m.candidate_e2[k] = e2
                m.candidate_image[k] = image
                m.candidate_normal[k] = normal
                m.candidate_side[k] = (image - wa).dot(normal)

        return place_candidates

    def make_shields(self):
        """ti.func shields(i, j, d) -> True when a triangle near particle i or j (its contact
        candidates) lies across the line between their centres (``d`` = x_i - x_j, minimum
        image, m): a plate between two spheres, which then are not a contact (a zero-thickness
        paddle or flight would otherwise let the spheres on its two faces push each other
        through it). Only particles with mesh candidates look: per candidate, whether the two
        centres lie on the two sides of the triangle's plane (most fail here), then a
        segment-triangle intersection (Moeller & Trumbore 1997). It reads the candidates as
        placed this step (make_place_candidates)."""
        m = self

        @ti.func
        def crosses(k, segment):
            """Whether the segment from the image of entry k's particle nearest its triangle
            along ``segment`` (m) crosses that triangle."""
            side = m.candidate_side[k]
            across = segment.dot(m.candidate_normal[k])
            hit = False
            if side * (side + across) < 0.0:
                origin, wa = m.candidate_image[k], m.candidate_a[k]
                e1, e2 = m.candidate_e1[k], m.candidate_e2[k]
                pvec = segment.cross(e2)
                det = e1.dot(pvec)
                inv = 1.0 / det
                tvec = origin - wa
                u = tvec.dot(pvec) * inv
                qvec = tvec.cross(e1)
                v = segment.dot(qvec) * inv
                hit = u >= 0.0 and v >= 0.0 and u + v <= 1.0
            return hit

        @ti.func
        def shields(i, j, d):
            # every candidate triangle of either sphere, not only those touched at the last
            # step: a triangle across a segment shorter than 2 r is within r of one of its
            # ends, so it is touched now (a flag from the last step would be one step late)
            hit = False
            for k in range(m.mesh_start[i], m.mesh_start[i] + m.mesh_count[i]):
                if not hit:
                    hit = crosses(k, -d)
            for k in range(m.mesh_start[j], m.mesh_start[j] + m.mesh_count[j]):
                if not hit:
                    hit = crosses(k, d)
            return hit

        return shields

    # --------------------------------------------------------------- driver
    def update_frames(self, time: float):
        self.frames.update_frames(time)

    def save_rows(self, n: int):
        """Before particles are reordered: remember the rows, flush the particles' loads."""
        self._flush_loads(n)
        self._save_rows(n)

    def rebuild_rows(self, n: int, time: float):
        """Re-bin the triangles at ``time`` and find each particle's candidate triangles."""
        self.frames.update_frames(time)
        items = int(self._count_bins())
        if items > self.items_capacity:
            self._alloc_items(bucket(int(items * LIST_GROWTH) + 16))
            self._compile_binning()
        self._fill_bins()
        longest = int(self._find_candidates(n))
        if longest > self.scratch_width:
            self._alloc_scratch(bucket(int(longest * LIST_GROWTH) + 1, floor=16))
            self._compile_rows()
            self._find_candidates(n)
        entries = int(self.mesh_start[n])
        grown = False
        if entries > self.entries_capacity:
            self._alloc_entries(grown_capacity(entries, n, self.e.state.capacity + 16))
            self._compile_rows()
            grown = True
        self._compact_and_carry(n)
        self.binned_time = time
        return grown

    def needs_rebinning(self, time: float) -> bool:
        """True when some body has moved half the skin since its triangles were binned."""
        half = 0.5 * self.e.model.skin
        return any(self.frames.kin.displacement(k, self.binned_time, time) > half
                   for k in range(self.n_bodies))

    def steps_before_rebinning(self, time: float, dt: float, most: int) -> int:
        """How many steps at ``time``, ``time + dt``, ... (at most ``most``, at least 1) the
        current binning serves: the largest m with no body moved half the skin by
        ``time + (m - 1) dt``. A bisection: the bound (kinematics.displacement) grows with
        time unless a body reverses within the span, which a run of steps (at most one output
        interval or factory batch) does not straddle in practice."""
        if most <= 1 or not self.needs_rebinning(time + (most - 1) * dt):
            return max(most, 1)
        good, bad = 1, most        # steps: good serves (time was checked), bad does not
        while bad - good > 1:
            mid = (good + bad) // 2
            if self.needs_rebinning(time + (mid - 1) * dt):
                bad = mid
            else:
                good = mid
        return good

    def take_loads(self, n: int):
        """Mean force (N) and torque about the axis point (N m) per body over the steps since
        the last call; resets the sums. ``n``: particles alive."""
        self._flush_loads(n)
        f, t, q = self.loads.take(self.interval_steps)
        self.interval_steps = 0
        return f, t, q
