"""Keys an effect adds to the scene's own sections (scene/keys.py ``Section.adds``, issue 46):
the heat transfer's material properties, temperatures and moistures, gravity's [simulation]
gravity. The host section reads them with their units and ranges, keeps them in its object's
``effect_values`` (read as attributes), the schema lists them, and a scene without the
effect's section refuses, notes or keeps each as the key declares (``Key.when_off``)."""
import math
import pickle

import numpy as np
import pytest

from test_loader import base, error, load
from taichi_dem.scene.keys import added_keys, registered
from taichi_dem.scene.schema import scene_schema
from taichi_dem.scene.sections.consistency import ignored_keys


def _heated():
    d = base()
    for m in d["materials"].values():
        m.update(thermal_conductivity="0.3 W/(m K)", heat_capacity="0.9 kJ/(kg K)")
    d["walls"][0]["temperature"] = "150 C"
    d["particles"][0]["temperature"] = "20 C"
    d["thermal"] = {"conduction": True, "wall_conduction": True}
    return d


def test_added_keys_are_read_by_their_host_with_units():
    s = load(_heated())
    ash = s.materials["ash"]
    assert ash.thermal_conductivity == pytest.approx(0.3)
    assert ash.heat_capacity == pytest.approx(900.0)
    assert ash.effect_values["heat_capacity"] == pytest.approx(900.0)
    assert s.walls[0].temperature == pytest.approx(423.15)
    assert s.fills[0].temperature == pytest.approx(293.15)
    # an absent added key reads as its declared default
    assert ash.emissivity is None and ash.surface_roughness == 0.0
    assert s.fills[0].moisture is None
    # the scene's own gravity, added by the gravity effect to [simulation]
    assert s.simulation.gravity == (0.0, 0.0, -9.81)


def test_an_added_key_is_checked_like_a_built_in_one():
    d = _heated()
    d["walls"][0]["temperature"] = "-300 C"
    error(d, "walls[0].temperature", "below absolute zero")
    d = _heated()
    d["materials"]["ash"]["heat_capacity"] = "3 m/s"
    error(d, "materials.ash.heat_capacity", "is a speed")
    d = _heated()
    d["walls"][0]["temprature"] = 300.0
    error(d, "walls[0].temprature", "unknown key", "temperature")


def test_a_misspelt_attribute_is_still_an_attribute_error():
    s = load(_heated())
    with pytest.raises(AttributeError):
        s.walls[0].temprature
    with pytest.raises(AttributeError):
        s.materials["ash"].thermal_conductivty


def test_scene_objects_with_added_keys_pickle():
    """Sweeps hand scenes to Dask workers: an object whose attributes come from
    ``effect_values`` must survive a pickle round trip."""
    s = load(_heated())
    wall, material = pickle.loads(pickle.dumps((s.walls[0], s.materials["ash"])))
    assert wall.temperature == pytest.approx(423.15)
    assert material.thermal_conductivity == pytest.approx(0.3)


def test_without_the_effect_each_key_does_what_it_declares():
    # "kept": a material keeps its properties where heat transfer is off
    d = _heated()
    del d["thermal"]
    s = load(d)
    assert s.materials["ash"].thermal_conductivity == pytest.approx(0.3)
    # "ignored": a temperature is a note for check and run, not an error
    notes = dict(ignored_keys(s))
    assert set(notes) == {"walls[0].temperature", "particles[0].temperature"}
    assert all("no [thermal] section (heat transfer off)" in r for r in notes.values())
    assert ignored_keys(load(_heated())) == []
    # "refused": a moisture or a coarse graining would do nothing
    d["particles"][0]["moisture"] = 0.1
    error(d, "particles[0].moisture", "drying needs heat transfer")
    d = _heated()
    del d["thermal"]
    d["materials"]["ash"]["coarse_grained"] = {"represented_diameter": "1 mm"}
    error(d, "materials.ash.coarse_grained", "is a heat law")


def test_a_check_among_added_keys_holds_with_the_effect_off():
    d = _heated()
    del d["thermal"]
    d["materials"]["ash"]["real_youngs_modulus"] = 1e6       # softer than the simulated 1.1e7
    error(d, "materials.ash.real_youngs_modulus", "must be >= youngs_modulus")


def test_the_schema_lists_added_keys_under_their_host():
    props = scene_schema()["properties"]
    material = props["materials"]["additionalProperties"]["properties"]
    assert material["thermal_conductivity"]["x-unit"] == "W/(m K)"
    assert material["coarse_grained"]["properties"]["represented_diameter"]["x-unit"] == "m"
    assert props["walls"]["items"]["properties"]["temperature"]["x-unit"] == "K"
    assert props["simulation"]["properties"]["gravity"]["default"] == [0.0, 0.0, -9.81]
    # gravity has no table of its own
    assert "gravity" not in props
    hosts = {host for host in ("materials.*", "walls[]", "bodies[]", "particles[]",
                               "factories[]", "simulation") if added_keys(host)}
    assert hosts == {"materials.*", "walls[]", "bodies[]", "particles[]", "factories[]",
                     "simulation"}
    assert "temperature" in registered()["walls[]"]


@pytest.mark.parametrize("g", [(0.0, 0.0, -9.81), (3.0, 0.0, -9.0), (0.0, 0.0, 0.0)])
def test_gravity_is_an_effect_enabled_by_its_key(g):
    """On where [simulation] gravity is nonzero; its declared bounds are what the time step
    read of the scene's gravity before: g along its direction over the domain's extent that
    way, and |g| as a resting particle's weight per unit mass."""
    from taichi_dem.effects.registry import effect_names
    from taichi_dem.setup.timestep import effect_bounds
    d = base()
    d["simulation"]["gravity"] = list(g)
    s = load(d)
    magnitude = math.sqrt(sum(a * a for a in g))
    assert ("gravity" in effect_names(s)) == (magnitude > 0)
    assert ("gravity" in s.settings) == (magnitude > 0)
    work, _, resting = effect_bounds(s)
    span = np.asarray(s.domain.max) - np.asarray(s.domain.min)
    expected = magnitude * float(np.dot(np.abs(g) / magnitude, span)) if magnitude else 0.0
    assert work == pytest.approx(expected, rel=1e-12)
    assert resting == pytest.approx(magnitude, rel=1e-12)
