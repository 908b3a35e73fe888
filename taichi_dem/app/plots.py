"""PNG plots of a results file (``taichi-dem plot RESULTS.h5 [--out DIR]``): what the demo
summaries print (``summaries.process_summary``), over time, titled and with units.

One PNG per figure, each written only when the file holds its series (CONTRACT.md's HDF5
layout, /series/... and /residence/...):

=================================  ====================================================
``particles.png``                  particle count and kinetic energy (J) - every run
``walls.png``                      plane walls that carried a load: force along the
                                   normal (N)
``body_<name>.png``                rotating bodies: axial torque (N m), drive power (W)
``residence_<sensor>.png``         residence-time distribution (s) of each
                                   residence-time sensor, mean / median / 10-90 % marked
``mass_flows.png``                 outlets', mass-flow sensors' and factories' flows
                                   (kg/s, per output interval) and the masses fed,
                                   removed and inside (kg)
``contacts.png``                   contact-count sensors
``collisions_<sensor>.png``        contact-statistics sensors, per pair kind: the
                                   contacts' normal force (N), the collision rate (1/s)
                                   and the collisions' impact speeds (m/s)
``temperatures.png``               mean particle temperature, each outlet's (of what it
                                   removed in the interval) and the gas leaving (K)
``moisture.png``                   drying: mean and outlet moisture (kg/kg), evaporated
``gas_profile.png``                plug-flow gas temperature along the axis (K) at four
                                   times (series gas/temperature)
``heat_flows.png``                 heat flow into each isothermal body and wall (W) and
                                   the wall-to-bed heat transfer coefficient (W/(m^2 K))
``energy_balance.png``             the thermal/* series (J): where the particles' heat
                                   went, and the energy inside, fed and removed
=================================  ====================================================

Every figure is described by a :class:`Figure` (title, panels, lines) before it is drawn, and
after drawing its ``drawn`` lists the data read back from the matplotlib artists, so a test
can compare what was plotted with the HDF5 series. Matplotlib runs headless (the Agg canvas;
pyplot is not used).
"""
from __future__ import annotations

import math
import os
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional

import numpy as np


from ..scene import catalog  # noqa: F401 (the effects' dimensions: a temperature)
from ..errors import ResultsFileError as PlotError      # missing, not HDF5, not taichi_dem's


@dataclass
class Line:
    label: str
    x: np.ndarray
    y: np.ndarray
    style: str = "-"          # matplotlib format string
    width: float = 1.2


@dataclass
class Panel:
    title: str
    xlabel: str
    ylabel: str
    lines: list = field(default_factory=list)                # Line
    hist: Optional[np.ndarray] = None                        # values of a histogram panel
    bins: Optional[np.ndarray] = None
    vlines: list = field(default_factory=list)               # (label, x)
    celsius: bool = False                                    # a second axis in C (panels in K)
    note: str = ""


@dataclass
class Figure:
    name: str                  # file stem
    title: str
    panels: list
    path: str = ""
    drawn: list = field(default_factory=list)   # per panel {label: (x, y)} or {"hist": ...}


def _safe(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", name).strip("_") or "x"


def _rate(t: np.ndarray, cumulative: np.ndarray,
          covered: Optional[np.ndarray] = None) -> tuple[np.ndarray, np.ndarray]:
    """The flow of a cumulative series per output interval (kg/s), at the interval's end; over
    what each sample covers (``sample_interval``: a short closing sample pooled with the
    interval before it, as the rate series are)."""
    from ..sensors.pooling import rate_of_cumulative
    return rate_of_cumulative(t, cumulative, covered)


class Results:
    """The parts of a results file the figures read: /series as numpy arrays, residence
    records, the scene's TOML text parsed."""

    def __init__(self, path: str):
        import h5py
        p = Path(path)
        if not p.exists():
            raise PlotError(f"{path}: no such file")
        if not p.is_file():
            raise PlotError(f"{path}: not a file")
        try:
            f = h5py.File(path, "r")
        except OSError as err:
            raise PlotError(f"{path}: cannot open as an HDF5 file ({str(err).splitlines()[0]}); "
                            f"give a taichi_dem results file (--h5)") from None
        with f:
            if "fields" in f and "host" in f:
                results = str(f.attrs.get("results", ""))
                raise PlotError(f"{path}: a taichi_dem checkpoint, not a results file; plot "
                                f"its results file" + (f" ({results})" if results else " (--h5)"))
            if "series" not in f or "time" not in f["series"]:
                raise PlotError(f"{path}: not a taichi_dem results file (it has no /series/time; "
                                f"give the file a run wrote with --h5)")
            self.series: dict[str, np.ndarray] = {}

            def grab(name, obj):
                if isinstance(obj, h5py.Dataset):
                    self.series[name] = obj[()]
            f["series"].visititems(grab)
            self.residence: dict[str, np.ndarray] = {}
            for name, g in (f["residence"].items() if "residence" in f else ()):
                if "t_in" in g and "t_out" in g:
                    self.residence[name] = g["t_out"][()] - g["t_in"][()]
            self.scene_text = str(f.attrs.get("scene", ""))
            self.version = str(f.attrs.get("taichi_dem_version", ""))
        if len(self.series["time"]) == 0:
            raise PlotError(f"{path}: the results file has no samples yet (/series/time is empty)")
        try:
            self.scene = tomllib.loads(self.scene_text)
        except tomllib.TOMLDecodeError:
            self.scene = {}
        self.path = path
        self.t = np.asarray(self.series["time"], float)
        self.label = Path(path).name
        first = self.scene_text.lstrip().splitlines()[0] if self.scene_text.strip() else ""
        self.description = first.lstrip("# ").strip() if first.startswith("#") else ""

    def names(self, group: str) -> list[str]:
        """The sorted names under /series/<group>/ (bodies, walls, sensors, outlets, ...)."""
        pre = group + "/"
        return sorted({k[len(pre):].split("/")[0] for k in self.series if k.startswith(pre)})

    def get(self, key: str) -> Optional[np.ndarray]:
        v = self.series.get(key)
        return None if v is None else np.asarray(v, float)

    def time_scale(self) -> float:
        th = self.scene.get("thermal", {})
        try:
            return float(th.get("time_scale", 1.0)) if isinstance(th, dict) else 1.0
        except (TypeError, ValueError):
            return 1.0


# ------------------------------------------------------------------------------ figures
def particles_figure(r: Results) -> Optional[Figure]:
    panels = []
    if r.get("particles/count") is not None:
        panels.append(Panel("particles in the domain", "time, s", "particles",
                            [Line("count", r.t, r.get("particles/count"))]))
    if r.get("particles/kinetic_energy") is not None:
        panels.append(Panel("kinetic energy", "time, s", "kinetic energy, J",
                            [Line("translational + rotational", r.t,
                                  r.get("particles/kinetic_energy"))]))
    return Figure("particles", "Particles", panels) if panels else None


def wall_figure(r: Results) -> Optional[Figure]:
    """The load on each plane wall: the force the particles press into it along its normal
    (N; the weight a floor carries), for walls that carried any."""
    normals = {w.get("name"): w.get("plane", {}).get("normal")
               for w in r.scene.get("walls", []) if isinstance(w, dict)}
    lines = []
    for name in r.names("walls"):
        force = r.get(f"walls/{name}/force")
        n = normals.get(name)
        if force is None or force.ndim != 2 or not isinstance(n, list) or len(n) != 3:
            continue
        n = np.asarray(n, float) / np.linalg.norm(np.asarray(n, float))
        load = -(force @ n)
        if np.any(load != 0.0):
            lines.append(Line(f"wall '{name}'", r.t, load))
    if not lines:
        return None
    return Figure("walls", "Loads on the plane walls",
                  [Panel("force pressed into each wall along its normal", "time, s", "load, N",
                         lines)])


def body_figures(r: Results) -> list[Figure]:
    """Per rotating body (a non-zero angular speed at some sample): axial torque and drive
    power over time, with the mean over the last quarter (the summaries' window)."""
    out = []
    for name in r.names("bodies"):
        p = f"bodies/{name}/"
        w, tq, pw = r.get(p + "angular_speed"), r.get(p + "axial_torque"), r.get(p + "power")
        if w is None or tq is None or not np.any(w != 0.0):
            continue
        start = len(r.t) - max(1, len(r.t) // 4)
        rpm = w * 60.0 / (2.0 * math.pi)
        t_tq = Panel(f"axial torque on '{name}' (mean of the last quarter "
                     f"{np.mean(tq[start:]):.4g} N m)", "time, s", "axial torque, N m",
                     [Line("axial torque", r.t, tq)])
        t_tq.lines.append(Line("mean, last quarter", r.t[start:],
                               np.full(len(r.t) - start, np.mean(tq[start:])), "--", 1.0))
        panels = [t_tq]
        if pw is not None:
            panels.append(Panel(f"drive power (mean of the last quarter {np.mean(pw[start:]):.4g} W)",
                                "time, s", "drive power, W", [Line("power", r.t, pw),
                                Line("mean, last quarter", r.t[start:],
                                     np.full(len(r.t) - start, np.mean(pw[start:])), "--", 1.0)]))
        panels.append(Panel("speed", "time, s", "speed, rpm", [Line("speed", r.t, rpm)]))
        out.append(Figure(f"body_{_safe(name)}", f"Body '{name}': shaft torque and drive power",
                          panels))
    return out


def residence_figures(r: Results) -> list[Figure]:
    """Per residence-time sensor: the histogram of t_out - t_in over every particle that
    completed the path, with the mean, median and 10 / 90 % percentiles."""
    out = []
    for name, rt in sorted(r.residence.items()):
        rt = np.asarray(rt, float)
        if len(rt) == 0:
            continue
        bins = np.histogram_bin_edges(rt, bins=min(60, max(5, int(math.sqrt(len(rt))) + 1)))
        p10, p50, p90 = np.percentile(rt, [10, 50, 90])
        mean = float(np.mean(rt))
        src = ""
        for x in r.scene.get("sensors", []):
            if isinstance(x, dict) and x.get("name") == name and "from" in x:
                src = f" ({x['from']} -> {x.get('to', '?')})"
        panel = Panel(f"{len(rt)} particles: mean {mean:.3g} s, median {p50:.3g} s, "
                      f"10-90 % {p10:.3g} - {p90:.3g} s", "residence time, s", "particles",
                      hist=rt, bins=bins,
                      vlines=[(f"mean {mean:.3g} s", mean), (f"median {p50:.3g} s", p50),
                              (f"10 % {p10:.3g} s", p10), (f"90 % {p90:.3g} s", p90)])
        out.append(Figure(f"residence_{_safe(name)}",
                          f"Residence-time distribution '{name}'{src}", [panel]))
    return out


def mass_flow_figure(r: Results) -> Optional[Figure]:
    """Flows per output interval (kg/s): each outlet's, each mass-flow sensor's and each
    factory's (from the mass it fed); below, the cumulative masses (kg)."""
    rates, masses = [], []
    for name in r.names("factories"):
        m = r.get(f"factories/{name}/mass")
        if m is not None:
            rates.append(Line(f"factory '{name}' (fed)", *_rate(r.t, m, r.series.get("sample_interval"))))
            masses.append(Line(f"fed by '{name}'", r.t, m))
    for name in r.names("outlets"):
        f = r.get(f"outlets/{name}/mass_flow")
        if f is not None:
            rates.append(Line(f"outlet '{name}'", r.t, f))
        m = r.get(f"outlets/{name}/mass")
        if m is not None:
            masses.append(Line(f"removed by '{name}'", r.t, m))
    for name in r.names("sensors"):
        f = r.get(f"sensors/{name}/mass_flow")
        if f is not None:
            rates.append(Line(f"sensor '{name}' (plane)", r.t, f, "-", 0.9))
    if not rates:
        return None
    inside = r.get("particles/mass")
    if inside is not None:
        masses.append(Line("inside", r.t, inside))
    lost = r.get("particles/lost_mass")
    if lost is not None and np.any(lost > 0):
        masses.append(Line("lost (left the domain)", r.t, lost))
    panels = [Panel("mass flows per output interval (x 3.6 = t/h)", "time, s", "mass flow, kg/s",
                    rates)]
    if masses:
        panels.append(Panel("masses", "time, s", "mass, kg", masses))
    return Figure("mass_flows", "Mass flows", panels)


def contact_figure(r: Results) -> Optional[Figure]:
    lines = [Line(f"particles touching ('{n}')", r.t, r.get(f"sensors/{n}/contact_count"))
             for n in r.names("sensors") if f"sensors/{n}/contact_count" in r.series]
    if not lines:
        return None
    return Figure("contacts", "Contact counts",
                  [Panel("particles touching a body", "time, s", "particles", lines)])


_PAIR_KINDS = (("particle", "particle-particle"), ("wall", "particle-wall"),
               ("body", "particle-body"))


def contact_statistics_figures(r: Results) -> list[Figure]:
    """Per contact-statistics sensor: the normal force of the contacts now (mean and 90th
    percentile, N), the collisions begun per second, and their impact speeds (median and
    90th percentile, m/s), one line per pair kind that had any contact or collision."""
    out = []
    for name in r.names("sensors"):
        base = f"sensors/{name}"
        if f"{base}/particle/contacts" not in r.series:
            continue
        force, rate, speed = [], [], []
        for kind, words in _PAIR_KINDS:
            get = (lambda stat: r.get(f"{base}/{kind}/{stat}"))
            contacts, collisions = get("contacts"), get("collisions")
            if contacts is not None and np.any(contacts > 0):
                force.append(Line(f"{words}, mean", r.t, get("normal_force_mean")))
                force.append(Line(f"{words}, 90 %", r.t, get("normal_force_p90"), "--", 0.9))
            if collisions is not None and np.any(collisions > 0):
                rate.append(Line(words, r.t, get("collision_rate")))
                speed.append(Line(f"{words}, median", r.t, get("impact_speed_p50")))
                speed.append(Line(f"{words}, 90 %", r.t, get("impact_speed_p90"), "--", 0.9))
        panels = [Panel("normal force of the contacts now", "time, s", "force, N", force),
                  Panel("collisions begun per second", "time, s", "rate, 1/s", rate),
                  Panel("impact speed (relative normal speed as a collision begins)", "time, s",
                        "speed, m/s", speed)]
        panels = [p for p in panels if p.lines]
        if panels:
            out.append(Figure(f"collisions_{_safe(name)}", f"Contact statistics '{name}'",
                              panels))
    return out


def temperature_figure(r: Results) -> Optional[Figure]:
    """Mean particle temperature, each outlet's (what it removed in the interval; gaps where
    nothing left) and the plug-flow gas leaving the domain, K (right axis C)."""
    lines = []
    mean = r.get("particles/mean_temperature")
    if mean is not None:
        lines.append(Line("particles, mean", r.t, mean))
    for name in r.names("outlets"):
        tt = r.get(f"outlets/{name}/mean_temperature")
        if tt is not None:
            lines.append(Line(f"outlet '{name}' (removed in the interval)", r.t, tt, ".-"))
    gas = r.get("gas/outlet_temperature")
    if gas is not None:
        lines.append(Line("gas leaving the domain", r.t, gas, "--"))
    if not lines:
        return None
    return Figure("temperatures", "Temperatures",
                  [Panel("mean and outlet temperatures", "time, s", "temperature, K", lines,
                         celsius=True)])


def moisture_figure(r: Results) -> Optional[Figure]:
    lines = []
    if r.get("particles/mean_moisture") is not None:
        lines.append(Line("particles, mean", r.t, r.get("particles/mean_moisture")))
    for name in r.names("outlets"):
        x = r.get(f"outlets/{name}/mean_moisture")
        if x is not None:
            lines.append(Line(f"outlet '{name}'", r.t, x, ".-"))
    if not lines:
        return None
    panels = [Panel("moisture (water per dry solid)", "time, s", "moisture, kg/kg", lines)]
    ev = r.get("particles/evaporated_mass")
    if ev is not None:
        panels.append(Panel("water evaporated", "time, s", "mass, kg",
                            [Line("evaporated so far", r.t, ev)]))
    return Figure("moisture", "Moisture", panels)


def gas_profile_positions(r: Results, cells: int) -> tuple[np.ndarray, float, str, float]:
    """Where each cell's gas/temperature value is (m along the axis: the face the gas leaves
    the cell by), the inlet temperature (K, NaN if unknown), the flow direction, the length."""
    from ..scene.units import parse_quantity
    g = r.scene.get("thermal", {}).get("gas", {}) if isinstance(r.scene.get("thermal"), dict) else {}
    try:
        length = parse_quantity(g.get("length", cells), "length")
    except Exception:  # noqa: BLE001  (a scene text that does not parse: plot by cell)
        length = float(cells)
    try:
        t_in = parse_quantity(g["inlet_temperature"], "temperature")
    except Exception:  # noqa: BLE001
        t_in = math.nan
    flow = g.get("flow", "along_axis")
    dx = length / cells
    k = np.arange(cells, dtype=float)
    x = (k + 1.0) * dx if flow == "along_axis" else k * dx
    return x, t_in, flow, length


def gas_profile_figure(r: Results) -> Optional[Figure]:
    """The plug-flow gas temperature along the axis (the gas leaving each cell, K) at a
    quarter, half, three quarters and the end of the run, with the inlet."""
    tg = r.get("gas/temperature")
    if tg is None or tg.ndim != 2 or tg.shape[0] == 0:
        return None
    cells = tg.shape[1]
    x, t_in, flow, length = gas_profile_positions(r, cells)
    n = len(r.t)
    picks = sorted({max(0, min(n - 1, int(round(f * n)) - 1)) for f in (0.25, 0.5, 0.75, 1.0)})
    lines = []
    x_in = 0.0 if flow == "along_axis" else length
    for i in picks:
        xs, ys = x, tg[i]
        if math.isfinite(t_in):            # the inlet face, at the inlet temperature
            xs, ys = (np.append(x_in, x), np.append(t_in, ys)) if flow == "along_axis" else \
                     (np.append(x, x_in), np.append(ys, t_in))
        lines.append(Line(f"t = {r.t[i]:.4g} s", xs, ys, "o-" if i == picks[-1] else ".-",
                          2.0 if i == picks[-1] else 1.0))
    arrow = "->" if flow == "along_axis" else "<-"
    return Figure("gas_profile", "Plug-flow gas temperature along the axis",
                  [Panel(f"gas flowing {flow.replace('_', ' ')} ({arrow}), entering at "
                         f"{t_in:.4g} K; values at the face the gas leaves each cell by",
                         "distance along the axis, m", "gas temperature, K", lines,
                         celsius=True)])


def heat_flow_figure(r: Results) -> Optional[Figure]:
    """Heat flow into each isothermal body and wall (W) and the wall-to-bed heat transfer
    coefficient of the bodies that record it (W/(m^2 K), NaN samples left out)."""
    flows, coefficients = [], []
    for group in ("bodies", "walls"):
        for name in r.names(group):
            q = r.get(f"{group}/{name}/heat_flow")
            if q is not None:
                flows.append(Line(f"{group[:-1] if group == 'walls' else 'body'} '{name}'", r.t, q))
            h = r.get(f"{group}/{name}/heat_transfer_coefficient")
            if h is not None:
                ok = np.isfinite(h)
                coefficients.append(Line(f"'{name}'", r.t[ok], h[ok], ".-"))
    if not flows:
        return None
    panels = [Panel("heat flow into isothermal walls and bodies", "time, s", "heat flow, W", flows)]
    if coefficients:
        panels.append(Panel("wall-to-bed heat transfer coefficient (heat flow / (covered area x "
                            "(mean bed - wall temperature)))", "time, s",
                            "heat transfer coefficient, W/(m^2 K)", coefficients))
    return Figure("heat_flows", "Heat flows into isothermal walls and bodies", panels)


def energy_balance_figure(r: Results) -> Optional[Figure]:
    """The thermal/* series: heat lost by the particles against heat into walls and bodies
    minus heat from the gas (they agree when the balance closes), and the energy inside, fed
    and removed (sum m c T, J)."""
    loss = r.get("thermal/particle_heat_loss")
    if loss is None:
        return None
    walls = r.get("thermal/wall_heat")
    gas = r.get("thermal/gas_heat")
    lines = [Line("heat out of the particles", r.t, loss, "-", 2.0)]
    if walls is not None:
        lines.append(Line("into isothermal walls and bodies", r.t, walls))
    if gas is not None and np.any(gas != 0):
        lines.append(Line("from the plug-flow gas", r.t, gas))
    if walls is not None:
        booked = walls - (gas if gas is not None else 0.0)
        lines.append(Line("walls - gas (booked)", r.t, booked, "--"))
        denom = max(abs(booked[-1]), abs(loss[-1]))
        err = f"; difference at the end {(loss[-1] - booked[-1]) / denom:.2%}" if denom > 0 else ""
    else:
        err = ""
    scale = r.time_scale()
    note = f" (thermal time: time_scale {scale:g})" if scale != 1.0 else ""
    panels = [Panel(f"where the particles' heat went{err}{note}", "time, s", "energy, J", lines)]
    stock = [Line(label, r.t, r.get(f"thermal/{key}")) for key, label in
             (("energy_inside", "inside (sum m c T)"), ("energy_fed", "fed"),
              ("energy_removed", "removed")) if f"thermal/{key}" in r.series]
    if stock:
        panels.append(Panel("thermal energy of the particles", "time, s", "energy, J", stock))
    return Figure("energy_balance", "Energy balance of the particles", panels)


def figures(r: Results) -> list[Figure]:
    """Every figure the results file has the series for, in reading order."""
    out: list[Figure] = []
    for make in (particles_figure, wall_figure, body_figures, residence_figures, mass_flow_figure,
                 contact_figure, contact_statistics_figures, temperature_figure, moisture_figure,
                 gas_profile_figure, heat_flow_figure, energy_balance_figure):
        got = make(r)
        out.extend(got if isinstance(got, list) else [got] if got is not None else [])
    return out


# ------------------------------------------------------------------------------ drawing
def draw(fig_data: Figure, r: Results, path: str, dpi: int = 100) -> None:
    """Draw ``fig_data`` to the PNG ``path`` on the Agg canvas and record in
    ``fig_data.drawn`` the data of the artists drawn (per panel {label: (x, y)}; a histogram
    panel {"hist": (bin edges, counts)})."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure as MplFigure

    n = len(fig_data.panels)
    fig = MplFigure(figsize=(8, 2.2 + 2.6 * n))
    FigureCanvasAgg(fig)
    axes = fig.subplots(n, 1, squeeze=False)[:, 0]
    fig_data.drawn = []
    for ax, panel in zip(axes, fig_data.panels):
        drawn = {}
        if panel.hist is not None:
            counts, edges, _ = ax.hist(panel.hist, bins=panel.bins, color="tab:blue", alpha=0.8,
                                       edgecolor="white")
            drawn["hist"] = (np.asarray(edges), np.asarray(counts))
            for (label, x), colour in zip(panel.vlines, ("k", "tab:red", "0.5", "0.5")):
                ax.axvline(x, color=colour, ls="--" if "%" in label else "-", lw=1.2, label=label)
        for line in panel.lines:
            if len(line.x) == 0:
                continue
            artist, = ax.plot(line.x, line.y, line.style, lw=line.width, label=line.label, ms=3)
            drawn[line.label] = (np.asarray(artist.get_xdata(), float),
                                 np.asarray(artist.get_ydata(), float))
        ax.set_title(panel.title, fontsize=9)
        ax.set_xlabel(panel.xlabel)
        ax.set_ylabel(panel.ylabel)
        ax.grid(True, alpha=0.3)
        if panel.celsius:
            sec = ax.secondary_yaxis("right", functions=(lambda k: k - 273.15, lambda c: c + 273.15))
            sec.set_ylabel("C")
        if len(panel.lines) + len(panel.vlines) > 1 or panel.hist is not None:
            ax.legend(fontsize=7, loc="best")
        fig_data.drawn.append(drawn)
    head = fig_data.title + f" - {r.label}"
    if r.description:
        head += "\n" + (r.description if len(r.description) < 110 else r.description[:107] + "...")
    fig.suptitle(head, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    fig_data.path = path


def default_dir(h5_path: str) -> str:
    """Where the plots of ``h5_path`` go by default: <results stem>_plots/ beside it."""
    p = Path(h5_path)
    return str(p.with_name(p.stem + "_plots"))


def plot_results(h5_path: str, out_dir: Optional[str] = None, dpi: int = 100) -> list[Figure]:
    """Write the PNGs of the results file ``h5_path`` into ``out_dir`` (default
    :func:`default_dir`) and return their :class:`Figure` data (``path`` set, ``drawn`` the
    plotted data). Raises :class:`PlotError` for a missing or foreign file."""
    r = Results(h5_path)
    out_dir = out_dir or default_dir(h5_path)
    os.makedirs(out_dir, exist_ok=True)
    made = figures(r)
    for fd in made:
        draw(fd, r, str(Path(out_dir) / f"{fd.name}.png"), dpi=dpi)
    return made


def add_arguments(p) -> None:
    p.add_argument("results", help="a results file (HDF5, as --h5 writes)")
    p.add_argument("--out", help="directory for the PNGs (default: <results stem>_plots/ beside it)")
    p.add_argument("--dpi", type=int, default=100, help="resolution of the PNGs, dots per inch (default 100)")


def cmd_plot(args) -> int:
    import sys
    try:
        made = plot_results(args.results, args.out, dpi=args.dpi)
    except PlotError as err:
        print(f"taichi-dem: {err}", file=sys.stderr)
        return 2
    out_dir = args.out or default_dir(args.results)
    print(f"plots: {len(made)} PNGs in {out_dir}")
    for fd in made:
        print(f"  {Path(fd.path).name:28s} {fd.title}")
    return 0
