"""The gas-gap effects (gas_gap.py's laws, first_layer.py's wall law), registered like every
other effect (thermal/effects.py lists them in a scene's step):

  GasGapWall   particle-wall and particle-body, through the gas gap (contact stage)
  GasGapPair   particle-particle, through the gas in the fluid lens (contact stage)
"""
from __future__ import annotations

import math

import numpy as np
import taichi as ti

from taichi_dem.effects.base import Effect
from taichi_dem.setup.tuning import MOST_SPECIES

from . import coarse_grained as coarse
from . import first_layer
from . import gas_gap
from .particle_transient import (FIRST_TIME, LAST_TIME, RATIO_TIMES, conductance_ratio,
                                 half_pair_conductance)

# the time each particle has rested against a heat-exchanging wall (WallContactAge counts it):
# declared by the "schlunder" wall law and the coarse-grained one alike
WALL_AGE_FIELDS = {"wall_contact_steps": (False, "int"), "wall_touch": (False, "int")}

# the partner's share of a pair's heat, stored at the owner's entry (heat W, conductance W/K):
# declared by the contact conduction and this effect alike
PAIR_SHARE = {"partner_heat": (False, "real"), "pair_conductance": (False, "real")}


def _skips_coarse(effect, ctx):
    """ti.func (contact) -> 1 where ``effect`` must leave the particle alone (a coarse-grained
    material: CoarseGrainedWall stands in), else 0; a constant 0 when the scene has none."""
    if not getattr(effect, "skip_coarse", False):
        @ti.func
        def never(c):
            return 0
        return never
    alpha_ws = ctx.table["coarse_alpha_ws"]

    @ti.func
    def coarse_grained(c):
        out = 0
        if alpha_ws[c.material_i, c.material_j] > 0.0:
            out = 1
        return out
    return coarse_grained


def _as_uploaded(ctx, name):
    """The material-pair table ``name`` as the device holds it (cast to the scene's precision),
    in f64 on the host: what reading the field back would give, without a copy kernel."""
    npf = np.float64 if ctx.real == ti.f64 else np.float32
    return np.asarray(ctx.table_values[name]).astype(npf).astype(np.float64)


def _gas_over_solid(scene, tables, k_gas):
    """(M, M) table: [a, b] = k_g / k_s of material a (the row's), for the solid-resistance
    gas-gap model; 0 where a material has no conductivity (then isothermal)."""
    names = tables.names
    out = np.zeros((len(names), len(names)))
    for a, name in enumerate(names):
        k_s = scene.materials[name].thermal_conductivity
        if k_s:
            out[a, :] = k_gas / k_s
    return out


# the gas-gap models that put the particles' own resistance in series along lines parallel to
# the axis (their k_g / k_s table); "schlunder" resolves it once (particle_transient.py)
SOLID_MODELS = ("solid_resistance", "voronoi")


def _gap_offsets(scene, tables, free_path):
    """(M, M) table: [a, b] = l + delta_a + delta_b (m), the "schlunder" law's widening of
    every gap: the gas's modified mean free path and the two surfaces' roughness."""
    names = tables.names
    rough = [scene.materials[n].surface_roughness or 0.0 for n in names]
    return np.array([[free_path + rough[a] + rough[b] for b in range(len(names))]
                     for a in range(len(names))])


class _GasGap(Effect):
    """What the two gas-gap effects share: k_g (W/(m K)), the lens (radii, also the contact
    margin), the minimum gap (m), the model and, for the series model, the k_g/k_s table.

    In the step the gas-gap integral is looked up (gas_gap.py "tables"): one table per pair of
    particle species (``ctx.species``: (material index, radius m) of each species the scene
    holds or inserts), or per species against a wall, tabulated at set-up. Without a finite set
    (radii from a distribution) every contact integrates (Gauss-Legendre, as in the tests)."""

    stage = "contact"
    MOST_SPECIES = MOST_SPECIES       # (setup/tuning.py)
    margin_key = "thermal.gas_gap_lens"
    margin_advice = "use a thinner lens, gas_gap_pairs = false"

    def __init__(self, description, conductivity, lens, min_gap, model="solid_resistance",
                 porosity=0.4, coarse_materials=False, free_path=0.0):
        super().__init__(description)
        self.skip_coarse = bool(coarse_materials)    # (walls only) leave those particles alone
        self.parameters = (float(conductivity), float(lens), float(min_gap))
        self.margin = float(lens)
        self.model = model
        self.porosity = float(porosity)          # the "voronoi" model's packing porosity
        self.solid = model in SOLID_MODELS       # the particles' own resistance counts
        self.widened = model == "schlunder"      # gaps widened by l + delta, not clamped to S
        self.free_path = float(free_path)        # l (m), the "schlunder" law's
        self.tables = ("gas_over_solid",) if self.solid else ()
        if self.widened:
            self.tables = self.tables + ("gap_offset",)
        if self.skip_coarse:
            self.tables = self.tables + ("coarse_alpha_ws",)
        self.species_tabulated = None     # the species the tables are for (None: no tables)

    def table_values(self, scene, tables):
        out = {}
        if self.solid:
            out["gas_over_solid"] = _gas_over_solid(scene, tables, self.parameters[0])
        if self.widened:
            out["gap_offset"] = _gap_offsets(scene, tables, self.free_path)
        return out

    def _offsets(self, ctx):
        """l + delta_a + delta_b (m) of each material pair (the "schlunder" law), numpy."""
        return _as_uploaded(ctx, "gap_offset")

    def _tabulate(self, ctx) -> bool:
        species = getattr(ctx, "species", None)
        return species is not None and 0 < len(species) <= self.MOST_SPECIES

    def _allocate_tables(self, ctx, tree, prefix, shape):
        """Fields for the tables (shape + nodes) and their ranges (shape + 3: s_lo, s_hi,
        nodes per unit ln(1 + s/S))."""
        self.species_tabulated = ctx.species
        self.table = tree.add(prefix + "_table", ctx.real, shape + (gas_gap.TABLE_NODES,))
        self.table_range = tree.add(prefix + "_range", ctx.real, shape + (4,))

    def _ratios(self, ctx):
        """k_g / k_s of each material (0: isothermal), from the engine's table."""
        if not self.solid:
            return None
        return _as_uploaded(ctx, "gas_over_solid")[:, 0]

    def _kernel_inputs(self, ctx):
        """What both contact laws close over: (solid, voronoi, porosity, the k_g/k_s table,
        tabulated, species_of, table, table_range, the table's node count)."""
        solid = self.solid
        tabulated = self.species_tabulated is not None
        return (solid, self.model == "voronoi", self.porosity,
                ctx.table["gas_over_solid"] if solid else None, tabulated,
                self.species_func() if tabulated else None,
                self.table if tabulated else None, self.table_range if tabulated else None,
                gas_gap.TABLE_NODES)

    def species_func(self):
        """ti.func (material, radius) -> the kind's index in the tables, -1 if none."""
        species = self.species_tabulated

        @ti.func
        def species_of(material, radius):
            k = -1
            for q in ti.static(range(len(species))):
                if material == ti.static(species[q][0]) and ti.abs(
                        radius - ti.static(species[q][1])) <= ti.static(1e-5 * species[q][1]):
                    k = q
            return k

        return species_of


class GasGapWall(_GasGap):
    """Particle-fluid-wall conduction (gas_gap.py): through the gas between a particle and a
    wall or body within the fluid lens, touching or not; isothermal surfaces."""

    name = "gas_gap_wall"
    kinds = ("plane", "surface")

    def table_values(self, scene, tables):
        out = super().table_values(scene, tables)
        if self.skip_coarse:
            out["coarse_alpha_ws"] = coarse.tables_for(scene, tables)["coarse_alpha_ws"]
        return out

    def __init__(self, *args, first_layer_ratios=None, time_scale=1.0, **kwargs):
        super().__init__(*args, **kwargs)
        # "schlunder": {material: (a_s m^2/s, G(Fo)/G(0) at the RATIO_TIMES nodes)}
        # (particle_transient.py), read with each particle's time against the wall
        self.first_layer_ratios = first_layer_ratios or {}
        self.time_scale = float(time_scale)
        if self.widened:
            self.margin = first_layer.wall_reach(self.parameters[1])
            self.particle_fields = dict(WALL_AGE_FIELDS)

    def allocate(self, ctx, tree):
        if self.widened:
            m = len(ctx.material_names)
            self.ratio_table = tree.add("first_layer_ratio", ctx.real, (m, RATIO_TIMES))
            self.diffusivity = tree.add("first_layer_diffusivity", ctx.real, (m,))
        # the isothermal planes have closed forms: tables only for the models with the solid
        if self.solid and not self.widened and self._tabulate(ctx):
            self._allocate_tables(ctx, tree, "gas_gap_wall", (len(ctx.species),))

    def upload(self, ctx):
        writes = []
        if self.widened:
            names = list(ctx.material_names)
            ratios = np.ones((len(names), RATIO_TIMES))
            diffusivity = np.zeros(len(names))
            for a, name in enumerate(names):
                if name in self.first_layer_ratios:
                    diffusivity[a], ratios[a] = self.first_layer_ratios[name]
            npf = np.float64 if ctx.real == ti.f64 else np.float32
            writes += [(self.ratio_table, ratios.astype(npf)),
                       (self.diffusivity, diffusivity.astype(npf))]
        if self.species_tabulated is None:
            return writes
        _, lens, min_gap = self.parameters
        ratio = self._ratios(ctx)
        values, ranges = [], []
        for material, radius in self.species_tabulated:
            values.append(gas_gap.plane_table(radius, lens, min_gap, ratio[material],
                                              self.model, self.porosity))
            ranges.append(gas_gap.table_range(radius, radius, lens, min_gap) + (min_gap,))
        npf = np.float64 if ctx.real == ti.f64 else np.float32
        return writes + [(self.table, np.array(values, npf)),
                         (self.table_range, np.array(ranges, npf))]

    def contact_func(self, ctx):
        k_gas, lens, min_gap = self.parameters
        # the gas's conductivity read at run time (engine/values.py); the tables are per unit k
        k_gas_of = ctx.values.scalar("gap_gas_conductivity", k_gas)
        solid, voronoi, porosity, ratio, tabulated, species_of, table, table_range, last = \
            self._kernel_inputs(ctx)

        skip_coarse = _skips_coarse(self, ctx)
        widened = self.widened
        offset = ctx.table["gap_offset"] if widened else None
        reach = first_layer.wall_reach(lens)
        s = ctx.state
        ratio_table = self.ratio_table if widened else None
        diffusivity = self.diffusivity if widened else None
        # a step of thermal time, S dt (s), read at run time (engine/values.py)
        thermal_dt = ctx.values.scalar("thermal_dt", ctx.dt * self.time_scale)
        per_log = (RATIO_TIMES - 1) / math.log(LAST_TIME / FIRST_TIME)

        @ti.func
        def gas_gap_wall(c, out):
            distance = c.radius_i - c.normal_overlap
            if skip_coarse(c) != 0:
                pass
            elif ti.static(widened):
                # Schlünder's first layer (isothermal surfaces, gaps widened by l + delta),
                # times the particle's own transient resistance after its time at the wall
                value = first_layer.widened_gap_integral(c.radius_i, distance, reach,
                                                         offset[c.material_i, c.material_j])
                if value > 0.0:
                    i = c.particle
                    s.wall_touch[i] = 1
                    a_s = diffusivity[c.material_i]
                    factor = 1.0 + 0.0 * value
                    if a_s > 0.0:
                        # Fourier number at the middle of this step's thermal time
                        age = (s.wall_contact_steps[i] + 0.5) * thermal_dt()
                        fourier = ti.max(age * a_s / (c.radius_i * c.radius_i),
                                         ti.static(FIRST_TIME))
                        x = ti.min(ti.log(fourier / ti.static(FIRST_TIME)) * ti.static(per_log),
                                   ti.static(RATIO_TIMES - 1.0) - 1e-6)
                        k = ti.cast(x, ti.i32)
                        f = x - k
                        factor = ((1.0 - f) * ratio_table[c.material_i, k]
                                  + f * ratio_table[c.material_i, k + 1])
                    out.conductance += k_gas_of() * value * factor
            elif ti.static(solid):
                integrate = True
                value = 0.0 * distance
                if ti.static(tabulated):
                    k = species_of(c.material_i, c.radius_i)
                    if k >= 0:
                        index, fraction = gas_gap.table_position(
                            -c.normal_overlap, table_range[k, 0], table_range[k, 1],
                            table_range[k, 2], table_range[k, 3])
                        if index >= 0:
                            integrate = False
                            if index < last:
                                value = ((1.0 - fraction) * table[k, index]
                                         + fraction * table[k, index + 1])
                if integrate:
                    if ti.static(voronoi):
                        value = gas_gap.plane_voronoi_gap_integral(
                            c.radius_i, distance, lens, min_gap,
                            ratio[c.material_i, c.material_j], porosity)
                    else:
                        value = gas_gap.plane_solid_gap_integral(
                            c.radius_i, distance, lens, min_gap,
                            ratio[c.material_i, c.material_j])
                out.conductance += k_gas_of() * value
            else:
                out.conductance += k_gas_of() * gas_gap.plane_gap_integral(
                    c.radius_i, distance, lens, min_gap)
            return out

        return gas_gap_wall


class GasGapPair(_GasGap):
    """Particle-fluid-particle conduction (Rong & Horio 1999 as extended by Musser 2011;
    gas_gap.py): through the gas in the fluid lens around the pair, touching or not (pairs
    up to ``lens`` radii of the larger sphere apart are handed to the law); isothermal
    surfaces. The partner's share rides on the pair fields the contact conduction declares."""

    name = "gas_gap_pair"
    kinds = ("pair",)
    pair_fields = PAIR_SHARE

    def __init__(self, *args, solids=None, **kwargs):
        super().__init__(*args, **kwargs)
        if self.widened:
            self.tables = self.tables + ("pair_solid_share",)
        # "schlunder": (k_s W/(m K), delta m) of each material, in the tables' order once
        # known ({name: ...} until then)
        self.solids = solids or {}
        self.materials = None

    def allocate(self, ctx, tree):
        if self.widened:
            self.materials = [self.solids.get(name) for name in ctx.material_names]
        if self._tabulate(ctx):
            k = len(ctx.species)
            self._allocate_tables(ctx, tree, "gas_gap_pair", (k, k))

    def table_values(self, scene, tables):
        out = super().table_values(scene, tables)
        if self.widened:
            out["pair_solid_share"] = pair_solid_shares(scene, tables, self.free_path,
                                                        self.porosity)
        return out

    def share_by_separation(self, separations, kind_a, kind_b):
        """The solids' share of the pair's resistance at each surface separation (m): the
        halves of each particle (particle_transient.half_pair_conductance, the gap to the
        midplane widened by s / 2 + l / 2 + delta) in series, resolved at 16 separations and
        interpolated in ln(1 + s / l); overlaps take the touching pair's."""
        k_gas, lens, _ = self.parameters
        (solid_a, radius_a), (solid_b, radius_b) = kind_a, kind_b
        face = gas_gap.VORONOI_FACE * (1.0 - self.porosity) ** (-1.0 / 3.0)
        reach_sin = face / math.sqrt(face * face + 1.0)
        l = self.free_path
        nodes = np.concatenate([[0.0], np.geomspace(0.1 * l, max(lens * max(radius_a, radius_b),
                                                                  l), 15)])

        def share(solid, radius, s):
            if solid is None:
                return 1.0
            k_solid, roughness = solid
            half, gas = half_pair_conductance(radius, k_solid, k_gas,
                                              0.5 * (s + l) + roughness, reach_sin)
            return half / gas

        values = np.array([2.0 / (1.0 / share(solid_a, radius_a, s) + 1.0 / share(solid_b, radius_b, s))
                           for s in nodes])
        x = np.log1p(np.maximum(np.asarray(separations), 0.0) / l)
        return np.interp(x, np.log1p(nodes / l), values)

    def upload(self, ctx):
        if self.species_tabulated is None:
            return []
        _, lens, min_gap = self.parameters
        ratio = self._ratios(ctx)
        offsets = self._offsets(ctx) if self.widened else None
        species = self.species_tabulated
        n = len(species)
        values = np.zeros((n, n, gas_gap.TABLE_NODES))
        ranges = np.zeros((n, n, 4))
        for a in range(n):
            for b in range(a, n):
                (ma, ra), (mb, rb) = species[a], species[b]
                # "schlunder": the gap widened by l + delta_a + delta_b, the table's own
                gap = offsets[ma, mb] if offsets is not None else min_gap
                if self.widened:
                    # isothermal, widened, within the Voronoi cone; times the solids' share
                    # resolved at each separation (standing apart, the gas limits the pair more
                    # and the solids less)
                    v = gas_gap.pair_table(ra, rb, lens, gap, self.model, 0.0, 0.0,
                                           self.porosity)
                    v = v * self.share_by_separation(
                        gas_gap.table_separations(min(ra, rb), max(ra, rb), lens, gap),
                        (self.materials[ma], ra), (self.materials[mb], rb))
                elif ratio is None:
                    v = gas_gap.pair_table(ra, rb, lens, gap, "isothermal")
                else:
                    v = gas_gap.pair_table(ra, rb, lens, gap, self.model,
                                           ratio[ma], ratio[mb], self.porosity)
                values[a, b] = values[b, a] = v
                ranges[a, b] = ranges[b, a] = gas_gap.table_range(
                    min(ra, rb), max(ra, rb), lens, gap) + (gap,)
        npf = np.float64 if ctx.real == ti.f64 else np.float32
        return [(self.table, values.astype(npf)), (self.table_range, ranges.astype(npf))]

    def contact_func(self, ctx):
        k_gas, lens, min_gap = self.parameters
        # the gas's conductivity read at run time (engine/values.py); the tables are per unit k
        k_gas_of = ctx.values.scalar("gap_gas_conductivity", k_gas)
        solid, voronoi, porosity, ratio, tabulated, species_of, table, table_range, last = \
            self._kernel_inputs(ctx)
        widened = self.widened
        offset = ctx.table["gap_offset"] if widened else None
        share = ctx.table["pair_solid_share"] if widened else None

        @ti.func
        def gas_gap_pair(c, out):
            distance = c.radius_i + c.radius_j - c.normal_overlap
            integrate = True
            value = 0.0 * distance
            if ti.static(tabulated):
                a = species_of(c.material_i, c.radius_i)
                b = species_of(c.material_j, c.radius_j)
                if a >= 0 and b >= 0:
                    index, fraction = gas_gap.table_position(
                        -c.normal_overlap, table_range[a, b, 0], table_range[a, b, 1],
                        table_range[a, b, 2], table_range[a, b, 3])
                    if index >= 0:
                        integrate = False
                        if index < last:
                            value = ((1.0 - fraction) * table[a, b, index]
                                     + fraction * table[a, b, index + 1])
            if integrate:
                if ti.static(widened):
                    value = gas_gap.pair_voronoi_widened_gap_integral(
                        c.radius_i, c.radius_j, distance, lens,
                        offset[c.material_i, c.material_j], 0.0 * distance, 0.0 * distance,
                        porosity)
                elif ti.static(voronoi):
                    value = gas_gap.pair_voronoi_gap_integral(
                        c.radius_i, c.radius_j, distance, lens, min_gap,
                        ratio[c.material_i, c.material_j], ratio[c.material_j, c.material_i],
                        porosity)
                elif ti.static(solid):
                    value = gas_gap.pair_solid_gap_integral(
                        c.radius_i, c.radius_j, distance, lens, min_gap,
                        ratio[c.material_i, c.material_j], ratio[c.material_j, c.material_i])
                else:
                    value = gas_gap.pair_gap_integral(c.radius_i, c.radius_j, distance, lens,
                                                      min_gap)
            if ti.static(widened):
                if integrate:
                    # (the tables hold the share by separation; here: the touching pair's)
                    value *= share[c.material_i, c.material_j]
            out.conductance += k_gas_of() * value
            return out

        return gas_gap_pair


MODEL_WORDS = {"isothermal": "isothermal surfaces (Rong & Horio / Musser; Morris et al.)",
               "solid_resistance": "with the solid's resistance in series from the centre "
                                   "planes (Zhou, Yu & Zulli)",
               "voronoi": "with the solid's resistance in series from the Voronoi cones "
                          "(Cheng, Yu & Zulli)",
               "schlunder": "walls: Schlünder's isothermal first layer; pairs: the Voronoi "
                            "cones; gaps widened by the mean free path and roughness"}


def gas_gap_free_path(scene) -> float:
    """l (m) of the "schlunder" gas-gap law: ``gas_gap_free_path`` if given, else Schlünder's
    modified mean free path (thermal/correlations.py) of air at ``gas_pressure`` and the
    scene's reference temperature: the [thermal.gas] temperature if there is one, else the
    mean of the walls', bodies', fills' and factories' temperatures."""
    from .correlations import modified_mean_free_path
    th = scene.settings.get("thermal")
    if th.gas_gap_free_path is not None:
        return float(th.gas_gap_free_path)
    if th.gas is not None:
        temperature = th.gas.temperature
    else:
        known = [x.temperature for x in list(scene.walls) + list(scene.bodies)
                 + list(scene.fills) + list(scene.factories) if x.temperature is not None]
        temperature = sum(known) / len(known) if known else 300.0
    return modified_mean_free_path(temperature, th.gas_pressure, th.gap_gas_conductivity)


def _gap_words(th, free_path) -> str:
    """How the gap is bounded, for the effect's description."""
    if th.gas_gap_model == "schlunder":
        return f"gaps widened by l = {free_path:.3g} m (+ roughness)"
    return f"minimum gap {th.gas_gap_min_gap:g} m"


def _material_radii(scene) -> dict:
    """{particle material: the geometric mean of its smallest and largest radius (m)}: where
    the resolved particle (particle_transient.py) is solved for it."""
    radii: dict = {}
    for source in list(scene.fills) + list(scene.factories):
        lo, hi = source.smallest_radius, source.largest_radius
        a, b = radii.get(source.material, (lo, hi))
        radii[source.material] = (min(a, lo), max(b, hi))
    # (a source with no particles, e.g. an empty CSV, reports an infinite radius: left out,
    # its material then keeps the isothermal ratio 1)
    return {name: math.sqrt(lo * hi) for name, (lo, hi) in radii.items()
            if math.isfinite(lo) and math.isfinite(hi) and lo > 0.0}


def pair_solid_shares(scene, tables, free_path: float, porosity: float) -> np.ndarray:
    """(M, M) table: the "schlunder" pair law's factor on the isothermal gas gap, the solids'
    share of a pair's resistance resolved once: G_half / G_gas of each material's particle
    (particle_transient.half_pair_conductance: steady heat through the sphere from the
    midplane of one touching neighbour to the opposite one, the gas within the Voronoi cone,
    gaps to the midplane widened by l / 2 + delta), combined in series for a pair (the harmonic
    mean); 1 for materials that are not particles'."""
    th = scene.settings.get("thermal")
    face = gas_gap.VORONOI_FACE * (1.0 - porosity) ** (-1.0 / 3.0)   # r_ij / R
    reach_sin = face / math.sqrt(face * face + 1.0)        # r_sf / R of two touching spheres
    names = tables.names
    radii = _material_radii(scene)
    ratio = np.ones(len(names))
    for a, name in enumerate(names):
        if name in radii:
            m = scene.materials[name]
            half, gas = half_pair_conductance(radii[name], m.thermal_conductivity,
                                              th.gap_gas_conductivity,
                                              0.5 * free_path + (m.surface_roughness or 0.0),
                                              reach_sin)
            ratio[a] = half / gas
    return 2.0 / (1.0 / ratio[:, None] + 1.0 / ratio[None, :])


def first_layer_ratios(scene, free_path: float) -> dict:
    """{material: (a_s m^2/s, G(Fo)/G(0))}: the "schlunder" wall law's transient ratio
    (particle_transient.py) for each particle material, at the geometric mean of its smallest
    and largest radius (the ratio depends on the radius through Fo, which the kernel takes per
    particle, and weakly through l / R)."""
    th = scene.settings.get("thermal")
    reach = first_layer.wall_reach(th.gas_gap_lens)
    out = {}
    for name, radius in _material_radii(scene).items():
        m = scene.materials[name]
        _, ratio, _ = conductance_ratio(radius, m.thermal_conductivity, m.density,
                                        m.heat_capacity, th.gap_gas_conductivity,
                                        free_path + (m.surface_roughness or 0.0), reach)
        out[name] = (m.thermal_conductivity / (m.density * m.heat_capacity), ratio)
    return out
