"""Every /series name a run can write, with its unit: declared once, by what writes it.

The sensors' and the run's series are declared here; an effect's own series are declared in
its settings module (``SERIES`` in effects/drag/settings.py, thermal/settings.py), beside its
scene keys, the heat transfer's among them even where a sensor writes them (the walls' and
bodies' heat flows, the energy balance, the outlets' temperatures). The results file gives every series dataset a ``units`` attribute from these
(sensors/units.py gathers the declarations; a name none matches gets none, and
tests/unit/test_series_units.py fails on it). Plain Python (no Taichi).

A name is a pattern: ``*`` stands for one name segment (a body's, a wall's, a sensor's).

``interval`` says how a sample's value relates to its output interval, so that a sample whose
interval is short (a run that stops between two regular samples) can be pooled with the one
before it (sensors/pooling.py): "" an instantaneous or cumulative value; "mean" a time mean
over the interval (a rate); "total" an amount in the interval (a count); "weighted" a mean
over what the interval saw, weighted by the amount of the sibling series ``weight``
(an outlet's temperature by its mass flow); "records" a statistic of the records closed in the
interval, pooled by the sensor that writes it.
"""
from __future__ import annotations

# (the declaration itself is data, beside the scene keys: effects declare series too)
from ..scene.keys import Series  # noqa: F401

SERIES = (
    Series("time", "s", "simulated time of the sample"),
    Series("sample_interval", "s", "the time the sample's interval means and counts cover: the "
           "output interval (0 at the start); a sample after a short interval (a run that ends "
           "between two regular samples) covers it and the interval before it"),
    Series("particles/count", "1", "particles alive"),
    Series("particles/kinetic_energy", "J", "translational and rotational, of the moving ones"),
    Series("particles/lost", "1", "particles that left the domain so far"),
    Series("particles/lost_mass", "kg", "mass that left the domain so far"),
    Series("particles/mass", "kg", "mass inside"),
    Series("bodies/*/force", "N", "on the body from the particles", "(3,)", interval="mean"),
    Series("bodies/*/torque", "N m", "about the body's rotation axis point", "(3,)",
           interval="mean"),
    Series("bodies/*/axial_torque", "N m", "the component along its rotation axis",
           interval="mean"),
    Series("bodies/*/angular_speed", "rad/s", "its prescribed angular speed"),
    Series("bodies/*/power", "W", "drive power, -axial_torque x angular_speed", interval="mean"),
    Series("bodies/*/covered_area", "m^2", "the area of its triangles the particles touch"),
    Series("walls/*/force", "N", "on the wall from the particles", "(3,)"),
    Series("sensors/*/mass_flow", "kg/s", "through the sensor's plane over the interval",
           interval="mean"),
    Series("sensors/*/crossings", "1", "particles that crossed the plane in the interval",
           interval="total"),
    Series("sensors/*/contact_count", "1", "particles touching the body"),
    *(s for kind, words in (("particle", "particle-particle"), ("wall", "particle-wall"),
                            ("body", "particle-body"))
      for s in (Series(f"sensors/*/{kind}/contacts", "1", f"{words} contacts now"),
                Series(f"sensors/*/{kind}/normal_force_mean", "N", f"{words}: the mean Hertz "
                       "normal force of the contacts now (from their overlaps)"),
                Series(f"sensors/*/{kind}/normal_force_p90", "N", f"{words}: its 90th percentile"),
                Series(f"sensors/*/{kind}/normal_force_max", "N", f"{words}: its largest"),
                Series(f"sensors/*/{kind}/normal_speed_mean", "m/s", f"{words}: the mean relative "
                       "normal speed of the contacts now"),
                Series(f"sensors/*/{kind}/normal_speed_p90", "m/s", f"{words}: its 90th percentile"),
                Series(f"sensors/*/{kind}/normal_speed_max", "m/s", f"{words}: its largest"),
                Series(f"sensors/*/{kind}/collisions", "1", f"{words} collisions begun in the "
                       "interval (counted at each contact's first touching step)",
                       interval="total"),
                Series(f"sensors/*/{kind}/collision_rate", "1/s", f"{words}: collisions "
                       "begun per second over the interval", interval="mean"),
                Series(f"sensors/*/{kind}/impact_speed_mean", "m/s", f"{words}: the mean "
                       "impact speed (relative normal speed as a collision begins) of the "
                       "interval's collisions", interval="weighted", weight="collisions"),
                Series(f"sensors/*/{kind}/impact_speed_p10", "m/s", f"{words}: its 10th "
                       "percentile (within a bin, 12 %)"),
                Series(f"sensors/*/{kind}/impact_speed_p50", "m/s", f"{words}: its median"),
                Series(f"sensors/*/{kind}/impact_speed_p90", "m/s", f"{words}: its 90th "
                       "percentile"),
                Series(f"sensors/*/{kind}/impact_speed_max", "m/s", f"{words}: the largest "
                       "impact speed in the interval"))),
    Series("sensors/*/count", "1", "residence records closed in the interval", interval="total"),
    Series("sensors/*/mean", "s", "residence time, mean over the interval's records",
           interval="records"),
    Series("sensors/*/median", "s", "residence time, median", interval="records"),
    Series("sensors/*/p10", "s", "residence time, 10th percentile", interval="records"),
    Series("sensors/*/p90", "s", "residence time, 90th percentile", interval="records"),
    Series("factories/*/mass", "kg", "inserted so far"),
    Series("factories/*/count", "1", "particles inserted so far"),
    Series("factories/*/behind", "kg", "mass the factory is behind its schedule"),
    Series("outlets/*/mass", "kg", "removed so far"),
    Series("outlets/*/count", "1", "particles removed so far"),
    Series("outlets/*/mass_flow", "kg/s", "removed over the interval", interval="mean"),
)
