"""What touches the bodies now, surveyed for the sensors and the run's checks: the particles
touching each body, the area of its triangles the bed covers, the deepest overlap on each.
Read-only: kernels over the mesh contacts' entries (mesh_contacts.py), compiled on first use
and again when those entries were reallocated."""

import numpy as np
import taichi as ti


class SurfaceSurvey:
    """The survey of one engine's mesh contacts ``mesh`` (MeshContacts)."""

    def __init__(self, mesh):
        self.m = mesh

    def contact_counts(self, n: int) -> np.ndarray:
        """Number of alive particles touching each body now (the heat-exchange surface's
        contacts of the seed study), (B,) int."""
        if getattr(self, "_count_for", None) is not self.m.mesh_contact:
            # (re)compiled when the entry arrays were reallocated
            self._count_for = self.m.mesh_contact
            m = self.m
            s = self.m.e.state
            nb = self.m.n_bodies
            if not hasattr(self, "touching"):
                counts = self.m.e.new_tree()
                self.touching = counts.add("touching", ti.i32, max(nb, 1))
                counts.finalize()
            touching = self.touching

            @ti.kernel
            def count_contacts(n: ti.i32, serial_loops: ti.template()):
                ti.loop_config(serialize=serial_loops)
                for b in range(nb):
                    touching[b] = 0
                ti.loop_config(serialize=serial_loops)
                for i in range(n):
                    if s.alive[i] != 0:
                        for b in ti.static(range(nb)):
                            touches = 0
                            for k in range(m.mesh_start[i], m.mesh_start[i] + m.mesh_count[i]):
                                if m.mesh_contact[k] != 0 and m.triangles.tri_body[m.mesh_tri[k]] == b:
                                    touches = 1
                            if touches != 0:
                                ti.atomic_add(touching[b], 1)
            self._count_contacts = self.m.e.serial_switch(count_contacts)
        self._count_contacts(n)
        return self.touching.to_numpy()[: self.m.n_bodies].astype(np.int64)

    def covered_areas(self, n: int) -> np.ndarray:
        """Per body, the area (m^2) of its triangles that at least one particle touches now,
        (B,): the surface the bed covers, for the wall-to-bed heat transfer coefficient. A
        triangle counts whole, so the figure is as fine as the mesh (a drum shell's triangles
        run the drum's length: right for a bed along the whole drum)."""
        if getattr(self, "_covered_for", None) is not self.m.mesh_contact:
            self._covered_for = self.m.mesh_contact
            m = self.m
            s = self.m.e.state
            if not hasattr(self, "touched"):
                tree = self.m.e.new_tree()
                self.touched = tree.add("touched_triangle", ti.i32, max(self.m.n_triangles, 1))
                tree.finalize()
            touched_triangle = self.touched

            @ti.kernel
            def mark_touched(n: ti.i32, serial_loops: ti.template()):
                ti.loop_config(serialize=serial_loops)
                for t in range(m.n_triangles):
                    touched_triangle[t] = 0
                ti.loop_config(serialize=serial_loops)
                for i in range(n):
                    if s.alive[i] != 0:
                        for k in range(m.mesh_start[i], m.mesh_start[i] + m.mesh_count[i]):
                            if m.mesh_contact[k] != 0:
                                touched_triangle[m.mesh_tri[k]] = 1      # benign race: all write 1
            self._mark_touched = self.m.e.serial_switch(mark_touched)
        if self.m.n_triangles == 0:
            return np.zeros(self.m.n_bodies)
        self._mark_touched(n)
        touched = self.touched.to_numpy()[: self.m.n_triangles] != 0
        return np.bincount(self.m.triangles.owner[touched], weights=self.m.triangles.area[touched],
                           minlength=self.m.n_bodies)[: self.m.n_bodies]

    def deepest_overlaps(self, n: int) -> np.ndarray:
        """Per body, the largest overlap of a touching particle now, as a fraction of that
        particle's radius, (B,). A large one means particles are pinched (a gap narrower than
        the particles, e.g. paddle tips and the shell)."""
        if getattr(self, "_deepest_for", None) is not self.m.mesh_overlap:
            self._deepest_for = self.m.mesh_overlap
            m = self.m
            s = self.m.e.state
            nb = self.m.n_bodies
            if not hasattr(self, "deepest"):
                tree = self.m.e.new_tree()
                self.deepest = tree.add("deepest", self.m.e.model.real, max(nb, 1))
                tree.finalize()
            deepest = self.deepest

            @ti.kernel
            def deepest_overlap(n: ti.i32, serial_loops: ti.template()):
                ti.loop_config(serialize=serial_loops)
                for b in range(nb):
                    deepest[b] = 0.0
                ti.loop_config(serialize=serial_loops)
                for i in range(n):
                    if s.alive[i] != 0:
                        for k in range(m.mesh_start[i], m.mesh_start[i] + m.mesh_count[i]):
                            if m.mesh_contact[k] != 0:
                                ti.atomic_max(deepest[m.triangles.tri_body[m.mesh_tri[k]]],
                                              m.mesh_overlap[k] / s.radius[i])
            self._deepest_overlap = self.m.e.serial_switch(deepest_overlap)
        self._deepest_overlap(n)
        return self.deepest.to_numpy()[: self.m.n_bodies].astype(np.float64)

