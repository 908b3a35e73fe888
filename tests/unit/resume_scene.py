"""A small scene for the checkpoint tests: 300 glass beads falling onto a floor and a
turning steel paddle, with conduction, wall/body conduction and convection."""

SCENE = """
[simulation]
end_time = 0.1
gravity = [0.0, 0.0, -9.81]
precision = "{precision}"
seed = 5

[domain]
min = [-0.06, -0.06, -0.06]
max = [0.06, 0.06, 0.12]

[[walls]]
name = "floor"
plane = {{ point = [0, 0, -0.055], normal = [0, 0, 1] }}
material = "steel"
temperature = 300.0

[materials.glass]
density = 2500.0
youngs_modulus = 1e7
poisson_ratio = 0.25
thermal_conductivity = 1.0
heat_capacity = 800.0

[materials.steel]
density = 7800.0
youngs_modulus = 2e11
poisson_ratio = 0.3
thermal_conductivity = 45.0
heat_capacity = 480.0

[[interactions]]
pair = ["glass", "glass"]
restitution = 0.5
friction = 0.5
rolling_friction = 0.05

[[interactions]]
pair = ["glass", "steel"]
restitution = 0.5
friction = 0.5
rolling_friction = 0.05

[[bodies]]
name = "paddle"
material = "steel"
temperature = 320.0
mesh = {{ builder = "box", min = [-0.03, -0.045, -0.004], max = [0.03, 0.045, 0.004], normals = "outward" }}
motion = {{ rotate = {{ axis_point = [0, 0, 0], axis_direction = [1, 0, 0], speed = "{speed}" }} }}

[[particles]]
material = "glass"
radius = 0.004
count = {count}
temperature = 400.0
region = {{ box = {{ min = [-0.05, -0.05, -0.053], max = [0.05, 0.05, 0.05] }} }}

[thermal]
conduction = true
wall_conduction = true
[thermal.gas]
model = "fixed"
temperature = 300.0

[output]
interval = 0.005
{extra}
"""


def scene_text(precision="f64", count=300, speed="60 rpm", extra=""):
    return SCENE.format(precision=precision, count=count, speed=speed, extra=extra)
