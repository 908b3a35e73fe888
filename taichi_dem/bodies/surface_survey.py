"""What touches the bodies now, surveyed for the sensors and the run's checks: the particles
touching each body, the area of its triangles the bed covers, the deepest overlap on each.
Read-only: one kernel over the mesh contacts' entries (mesh_contacts.py) fills all three,
compiled on first use and again when those entries were reallocated; one copy kernel reads
them and leaves them zero for the next survey (engine/transfer.take)."""

import numpy as np
import taichi as ti

from ..engine import transfer


class SurfaceSurvey:
    """The survey of one engine's mesh contacts ``mesh`` (MeshContacts)."""

    def __init__(self, mesh):
        self.m = mesh
        self._compiled_for = None

    def _compile(self):
        m = self.m
        s = m.e.state
        nb = m.n_bodies
        if not hasattr(self, "touching"):
            tree = m.e.new_tree()
            # per body: particles touching it now; the deepest overlap over the radius; per
            # triangle: 1 where a particle touches it (zero between surveys)
            self.touching = tree.add("touching", ti.i32, max(nb, 1))
            self.deepest = tree.add("deepest", m.e.model.real, max(nb, 1))
            self.touched = tree.add("touched_triangle", ti.i32, m.triangles.slots)
            tree.finalize()
        touching, deepest, touched_triangle = self.touching, self.deepest, self.touched

        @ti.kernel
        def survey(n: ti.i32, serial_loops: ti.template()):
            ti.loop_config(serialize=serial_loops)
            for i in range(n):
                if s.alive[i] != 0:
                    first, last = m.mesh_start[i], m.mesh_start[i] + m.mesh_count[i]
                    for b in ti.static(range(nb)):
                        touches = 0
                        for k in range(first, last):
                            if m.mesh_contact[k] != 0 and m.triangles.tri_body[m.mesh_tri[k]] == b:
                                touches = 1
                        if touches != 0:
                            ti.atomic_add(touching[b], 1)
                    for k in range(first, last):
                        if m.mesh_contact[k] != 0:
                            touched_triangle[m.mesh_tri[k]] = 1      # benign race: all write 1
                            ti.atomic_max(deepest[m.triangles.tri_body[m.mesh_tri[k]]],
                                          m.mesh_overlap[k] / s.radius[i])
        self._survey = m.e.serial_switch(survey)
        self._compiled_for = (m.mesh_contact, m.mesh_overlap)

    def _take(self, n: int):
        """(touching (B,) int, deepest (B,) float, touched (T,) bool) now."""
        done = self._compiled_for
        if done is None or done[0] is not self.m.mesh_contact or done[1] is not self.m.mesh_overlap:
            # (re)compiled when the entry arrays were reallocated
            self._compile()
        self._survey(n)
        touching, deepest, touched = transfer.take([self.touching, self.deepest, self.touched])
        nb = self.m.n_bodies
        return (touching[:nb].astype(np.int64), deepest[:nb].astype(np.float64),
                touched[: self.m.n_triangles] != 0)

    def contact_counts(self, n: int) -> np.ndarray:
        """Number of alive particles touching each body now (the heat-exchange surface's
        contacts of the seed study), (B,) int."""
        return self._take(n)[0]

    def covered_areas(self, n: int) -> np.ndarray:
        """Per body, the area (m^2) of its triangles that at least one particle touches now,
        (B,): the surface the bed covers, for the wall-to-bed heat transfer coefficient. A
        triangle counts whole, so the figure is as fine as the mesh (a drum shell's triangles
        run the drum's length: right for a bed along the whole drum)."""
        if self.m.n_triangles == 0:
            return np.zeros(self.m.n_bodies)
        touched = self._take(n)[2]
        return np.bincount(self.m.triangles.owner[touched], weights=self.m.triangles.area[touched],
                           minlength=self.m.n_bodies)[: self.m.n_bodies]

    def deepest_overlaps(self, n: int) -> np.ndarray:
        """Per body, the largest overlap of a touching particle now, as a fraction of that
        particle's radius, (B,). A large one means particles are pinched (a gap narrower than
        the particles, e.g. paddle tips and the shell)."""
        return self._take(n)[1]
