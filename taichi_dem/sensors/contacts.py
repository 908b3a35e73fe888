"""Contact counts (``[[sensors]] kind = "contact_count"``): how many particles touch a body
now (the heat-exchange surface's contacts of the seed study); /series
sensors/<name>/contact_count."""
from __future__ import annotations


class ContactCounts:
    def __init__(self, scene, engine):
        self.engine = engine
        self.sensors = [x for x in scene.sensors if x.kind == "contact_count"]
        self.body_names = [b.name for b in scene.bodies]

    def sample(self, values: dict, now) -> None:
        e = self.engine
        counts = e.mesh.survey.contact_counts(e.count)
        for x in self.sensors:
            values[f"sensors/{x.name}/contact_count"] = float(counts[self.body_names.index(x.body)])
