"""Impacts: the relative normal speed of each collision at its first touching step, counted
per pair kind, as EDEM's collision export records a collision's impact velocity. Enabled by a
``[[sensors]] kind = "contact_statistics"``, whose collision series it writes at every output
sample (``sample``: /series sensors/<name>/<kind>/collisions, collision_rate, impact_speed_*,
kind particle, wall or body) before it resets its counts; a scene without one neither
compiles nor runs it.

A contact is new while the value it carries (contact history, contacts/history.py) is zero:
the history of a contact is zeroed when it opens, carried across neighbour-list rebuilds and
from triangle to neighbouring triangle of the same body, so a collision is counted once, at
its first step, however long it lasts. The impact speed is the approach speed then, v_n =
-(v_i - v_partner) . n at the contact point (m/s; the velocity the step holds, which for a
free approach is the velocity of the last free flight). Counts are kept in logarithmic bins
(``BINS_PER_DECADE`` per decade from ``LOWEST`` m/s; bin 0 below it, the last bin above the
top) with the exact sum and largest per kind, so the mean and the largest are exact and a
percentile is exact to within one bin (a factor 10^(1/20) = 1.12).
"""
import numpy as np
import taichi as ti

from .base import Effect

KINDS = ("pair", "plane", "triangle")
LOWEST = 1e-5                     # m/s, the lower edge of the first decade
DECADES = 8                       # up to 1e3 m/s
BINS_PER_DECADE = 20
N_BINS = DECADES * BINS_PER_DECADE + 2


def bin_edges() -> np.ndarray:
    """The edges of bins 1 .. N_BINS - 2, m/s (bin 0 is below the first, the last above)."""
    return LOWEST * 10.0 ** (np.arange(DECADES * BINS_PER_DECADE + 1) / BINS_PER_DECADE)


class Impacts(Effect):
    name = "impacts"
    stage = "contact"
    kinds = KINDS
    mechanical = True
    per_kind = True
    # component 0: the impact speed (m/s), 1: 1 once counted (a zero-speed contact too)
    contact_fields = {"impact_history": (True, "real")}

    def __init__(self, description: str, sensors=()):
        super().__init__(description)
        self.sensors = tuple(sensors)   # the contact_statistics sensors' names
        self.histogram = {}             # {kind: bin counts} since the start (bin_edges)
        self._last_time = None          # s, the time of the last sample

    def allocate(self, ctx, tree) -> None:
        n = len(KINDS)
        self.counts = tree.add("impact_counts", ti.i32, n * N_BINS)
        self.speed_sum = tree.add("impact_speed_sum", ti.f64, n)   # m/s
        self.speed_max = tree.add("impact_speed_max", ti.f64, n)   # m/s

    def contact_func(self, ctx, kind: str):
        k = KINDS.index(kind)
        counts, speed_sum, speed_max = self.counts, self.speed_sum, self.speed_max
        log_lowest = float(np.log10(LOWEST))

        @ti.func
        def impact(c, out, history, dt):
            if history.impact[1] == 0.0:
                speed = ti.max(-c.v_rel.dot(c.normal), 0.0)
                # dt = 0: the start's evaluation of the initial state (a bed loaded packed, a
                # resting contact): contacts that exist then are no collisions, only marked
                if dt > 0.0:
                    b = 0
                    if speed >= LOWEST:
                        b = ti.min(ti.cast(ti.floor((ti.log(ti.cast(speed, ti.f64)) / ti.log(10.0)
                                                      - log_lowest) * BINS_PER_DECADE), ti.i32)
                                   + 1, N_BINS - 1)
                    ti.atomic_add(counts[k * N_BINS + b], 1)
                    ti.atomic_add(speed_sum[k], ti.cast(speed, ti.f64))
                    ti.atomic_max(speed_max[k], ti.cast(speed, ti.f64))
                history.impact[0] = speed
                history.impact[1] = 1.0
            return out, history

        return impact

    def take(self):
        """{kind: (bin counts, sum of speeds m/s, largest m/s)} since the last take, and the
        counts zeroed (host side, between steps)."""
        counts = self.counts.to_numpy().reshape(len(KINDS), N_BINS).astype(np.int64)
        sums, largest = self.speed_sum.to_numpy(), self.speed_max.to_numpy()
        self.counts.fill(0)
        self.speed_sum.fill(0.0)
        self.speed_max.fill(0.0)
        return {kind: (counts[k], float(sums[k]), float(largest[k]))
                for k, kind in enumerate(KINDS)}

    def sample(self, values: dict, n: int, measured: dict) -> None:
        """The collisions since the last sample, per pair kind, into each sensor's series
        (the rate over the time since then: the first sample of a run, or of a resumed one,
        takes the interval the run gives it)."""
        now = float(values["time"])
        interval = (now - self._last_time if self._last_time is not None
                    else float(values.get("sample_interval", 0.0)))
        self._last_time = now
        for law_kind, (counts, total, largest) in self.take().items():
            kind = SENSOR_KINDS[law_kind]
            self.histogram[kind] = self.histogram.get(kind, 0) + counts
            series = statistics(counts, total, largest, interval)
            for name in self.sensors:
                for stat, value in series.items():
                    values[f"sensors/{name}/{kind}/{stat}"] = value


# the sensor's names of the contact law's kinds
SENSOR_KINDS = {"pair": "particle", "plane": "wall", "triangle": "body"}


def statistics(counts, speed_sum: float, largest: float, interval: float) -> dict:
    """The collision series of one pair kind from the impacts' bin counts, the sum (m/s) and
    largest (m/s) of their speeds, over ``interval`` s (the rate is 0 for an empty one)."""
    n = int(np.sum(counts))
    return {"collisions": float(n), "collision_rate": n / interval if interval > 0 else 0.0,
            "impact_speed_mean": speed_sum / n if n else 0.0,
            "impact_speed_p10": percentile(counts, 10.0),
            "impact_speed_p50": percentile(counts, 50.0),
            "impact_speed_p90": percentile(counts, 90.0),
            "impact_speed_max": largest}


def percentile(counts, q: float) -> float:
    """The q-th percentile (0-100) of the speeds binned in ``counts`` (m/s): interpolated
    geometrically inside its bin (bin 0 reads as 0, the top bin as its lower edge)."""
    counts = np.asarray(counts, np.int64)
    total = int(counts.sum())
    if total == 0:
        return 0.0
    rank = q / 100.0 * total
    cumulative = np.cumsum(counts)
    b = int(np.searchsorted(cumulative, rank, side="left"))
    b = min(max(b, 0), len(counts) - 1)
    if b == 0:
        return 0.0
    edges = bin_edges()
    if b == len(counts) - 1:
        return float(edges[-1])
    below = cumulative[b - 1] if b > 0 else 0
    fraction = (rank - below) / counts[b] if counts[b] else 0.0
    lo, hi = edges[b - 1], edges[b]
    return float(lo * (hi / lo) ** min(max(fraction, 0.0), 1.0))
