"""Real sweeps and a tradeoff study on a LocalCluster of 2 workers (taichi_dem/app/sweep.py,
tradeoffs.py): each run is a fresh process on the 60-bead box (tests/unit/sweep_box.toml,
~2-4 s a run with a warm kernel cache). Checked: the table holds what each run's HDF5 says, a
failed (diverging) run is reported while the other finishes, a sweep killed with SIGKILL
resumes without re-running finished runs, a run continues from its checkpoint, and the
tradeoff report's numbers are the ones its runs produced."""
import csv
import json
import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from taichi_dem.app import overrides as ov
from taichi_dem.app import sweep, tradeoffs
from taichi_dem.app.outputs import key_outputs

HERE = Path(__file__).resolve().parent
BOX = str(HERE / "sweep_box.toml")
DURATION = 0.04          # s simulated per run: ~870 steps of 60 particles


@pytest.fixture(scope="module")
def client():
    c = sweep.make_client(workers=2)
    yield c
    sweep.close_client(c)


def _csv(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def test_sweep_table_matches_each_runs_results(client, tmp_path):
    combos = ov.combinations([ov.parse_set("interactions.0.friction=0.2,0.6")])
    specs = sweep.plan(BOX, combos, seeds=2, duration=DURATION)
    records = sweep.run_sweep(specs, str(tmp_path), client, progress=False)
    assert [r["status"] for r in records] == ["done"] * 4, [r.get("message") for r in records]
    csv_path, md_path = sweep.write_table(records, str(tmp_path), "t", "cmd")
    rows = _csv(csv_path)
    assert [(float(r["interactions.0.friction"]), int(r["seed"])) for r in rows] == [
        (0.2, 1), (0.2, 2), (0.6, 1), (0.6, 2)]
    for r, spec in zip(rows, specs):
        run = tmp_path / "runs" / spec.id
        assert (run / "done.json").exists() and (run / "checkpoint.h5").exists()
        out = key_outputs(str(run / "results.h5"))
        assert float(r["floor/load [N]"]) == pytest.approx(out["floor/load"], rel=1e-12)
        assert float(r["particles/kinetic_energy [J]"]) == pytest.approx(
            out["particles/kinetic_energy"], rel=1e-12)
        assert float(r["particles"]) == 60
        steps = round(DURATION / float(r["dt"]))
        assert float(r["particle_steps_per_s"]) == pytest.approx(
            steps * 60 / float(r["step_s"]), rel=0.01)
    # 40 ms in, the lowest beads have landed: the floor is pressed (never pulled), and the
    # beads' kinetic energy is below the potential energy of the fill, m g h < 0.016 J
    assert all(float(r["floor/load [N]"]) >= 0.0 for r in rows)
    assert all(0.0 < float(r["particles/kinetic_energy [J]"]) < 0.016 for r in rows)
    # seeds place the beads differently: the two seeds of one friction differ
    assert rows[0]["floor/load [N]"] != rows[1]["floor/load [N]"]
    md = md_path.read_text()
    assert md.count("\n| 0.") == 4 and "4 of 4 runs finished" in md


def test_failed_run_is_reported_and_the_other_finishes(client, tmp_path):
    """E = 5 kPa lets the beads sink through each other: the run diverges (exit 3). Run
    through ``scheduler=`` (the --scheduler path: a client of its own to an existing
    cluster, which stays up afterwards)."""
    combos = ov.combinations([ov.parse_set("materials.glass.youngs_modulus=5e6,5e3")])
    specs = sweep.plan(BOX, combos, duration=0.06)
    records = sweep.run_sweep(specs, str(tmp_path), scheduler=client.scheduler.address,
                              progress=False)
    assert client.submit(sum, [1, 2]).result() == 3          # the cluster is still there
    assert records[0]["status"] == "done"
    assert records[1]["status"] == "failed" and records[1]["rc"] == 3
    assert "diverged" in records[1]["message"] and "Traceback" not in records[1]["message"]
    _, md = sweep.write_table(records, str(tmp_path), "t", "cmd")
    assert "Failed runs:" in md.read_text() and specs[1].id in md.read_text()
    assert not (tmp_path / "runs" / specs[1].id / "done.json").exists()
    assert (tmp_path / "runs" / specs[1].id / "failed.json").exists()


def test_run_continues_from_its_checkpoint(tmp_path):
    """A run killed after its (final) checkpoint and before its finished marker is continued
    from the checkpoint, not re-run, and gives the same outputs."""
    spec = sweep.plan(BOX, [{}], duration=DURATION)[0]
    d = tmp_path / spec.id
    from dataclasses import asdict
    first = sweep.execute_run(asdict(spec), str(d))
    assert first["status"] == "done" and not first["resumed"]
    (d / "done.json").unlink()
    again = sweep.execute_run(asdict(spec), str(d))
    assert again["status"] == "done" and again["resumed"]
    assert again["steps"] == first["steps"]
    for k, v in first["outputs"].items():
        assert again["outputs"][k] == pytest.approx(v, rel=1e-12), k


def test_killed_sweep_resumes_without_rerunning_finished_runs(tmp_path):
    """`taichi-dem sweep` on one worker, killed (SIGKILL to its process group: the cluster
    goes too) once its first run has finished; the same command again skips that run."""
    out = tmp_path / "s"
    cmd = [sys.executable, "-m", "taichi_dem", "sweep", BOX, "--set",
           "interactions.0.friction=0.2,0.6", "--duration", str(DURATION), "--out", str(out),
           "--workers", "1"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            start_new_session=True)
    deadline = time.time() + 120
    while time.time() < deadline and not list(out.glob("runs/*/done.json")):
        time.sleep(0.1)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    finished = {p.parent.name: p.stat().st_mtime_ns for p in out.glob("runs/*/done.json")}
    assert len(finished) == 1, finished
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=180)
    assert res.returncode == 0, res.stderr
    assert "1 of 2 runs already finished" in res.stderr
    for name, mtime in finished.items():
        assert (out / "runs" / name / "done.json").stat().st_mtime_ns == mtime   # not re-run
    rows = _csv(out / "results.csv")
    assert len(rows) == 2 and all(r["status"] == "done" for r in rows)
    assert "results:" in res.stdout and (out / "sweep.md").exists()


def test_tradeoffs_report_numbers(client, tmp_path):
    """A tiny study (coarse graining, 2 seeds; the time-scale knob skipped: no heat): the report's
    errors and speed-ups are those of its runs, the coarse-grained runs have 1/f^3 the beads
    at f times the time step, and one PNG per output is written."""
    res = tradeoffs.run_tradeoffs(BOX, str(tmp_path), ["size", "time_scale"], seeds=2,
                                  duration=DURATION, tolerance=0.05, client=client,
                                  command="test", progress=False)
    recs = res["records"]
    assert all(r["status"] == "done" for r in recs), [r.get("message") for r in recs]
    ref, rows = res["reference"], {r.setting: r for r in res["rows"]}
    assert set(rows) == {"radius x1.5", "radius x2"}
    assert "no [thermal]" in res["skipped"]["time_scale"]

    def of(setting):
        return [r for r in recs if r["labels"]["setting"] == setting]
    ref_recs = of("reference")
    assert {r["precision"] for r in recs} == {"f64"}          # the reference's precision
    for name in ref.values:
        ref_med = float(np.median([r["outputs"][name] for r in ref_recs]))
        assert ref.values[name] == pytest.approx(ref_med)
        for setting, row in rows.items():
            med = float(np.median([r["outputs"][name] for r in of(setting)]))
            assert row.errors[name] == pytest.approx((med - ref_med) / abs(ref_med))
        xs = [r["outputs"][name] for r in ref_recs]
        assert res["scatter"][name] == pytest.approx(np.std(xs, ddof=1) / abs(np.mean(xs)))
    for row in rows.values():
        assert row.speedup == pytest.approx(ref.cpu_s / row.cpu_s)
        cpu = float(np.median([r["cpu_s"] for r in of(row.setting)]))
        assert row.cpu_s == pytest.approx(cpu) and 0 < cpu
    assert rows["radius x2"].particles == round(60 / 8)
    assert rows["radius x1.5"].particles == round(60 / 1.5 ** 3)
    # the contact-duration bound sets dt, and the Hertz contact time scales with the radius
    assert rows["radius x2"].dt == pytest.approx(2 * ref.dt, rel=1e-9)
    # coarser beads: other outputs (a different bed), an error that is not zero
    assert abs(rows["radius x2"].errors["particles/kinetic_energy"]) > 0

    md = res["report"].read_text()
    for setting, row in rows.items():
        line = next(l for l in md.splitlines() if l.startswith(f"| {setting} |"))
        assert f"{100 * row.errors['floor/load']:+.1f} %" in line
        assert f"| {row.speedup:.3g} |" in line
    assert "## size" in md and "Recommended" in md
    assert "time_scale" in md.split("## Skipped")[1]
    # the study restricted to one output: same numbers, one plot; an unknown name exits 2
    ref1, rows1, _ = tradeoffs.aggregate(recs, ["floor/load"])
    assert list(ref1.values) == ["floor/load"]
    assert rows1[0].errors["floor/load"] == rows[rows1[0].setting].errors["floor/load"]
    with pytest.raises(tradeoffs.SceneError, match="particles/kinetic_energy"):
        tradeoffs.aggregate(recs, ["drum/axial_torque"])
    import matplotlib.image
    assert len(res["plots"]) == len(ref.values)
    for p in res["plots"]:
        img = matplotlib.image.imread(p)
        assert img.shape[0] > 200 and img.shape[1] > 300
        assert img[..., :3].std() > 0.05            # not a blank canvas
        assert Path(p).name in md


def test_recommend_picks_the_fastest_within_tolerance():
    def row(setting, step, err):
        return tradeoffs.Row("k", setting, 2, [], 1e-5, 10, step_s=2 * step, wall_s=3 * step,
                             speedup=1.0 / step, values={"a": 1.0}, errors={"a": err}, cpu_s=step)
    ref = row("reference", 1.0, 0.0)
    rows = [row("x", 0.5, 0.03), row("y", 0.2, 0.2), row("z", 0.4, -0.04), row("w", 2.0, 0.0),
            row("v", 0.98, 0.0)]
    assert tradeoffs.recommend(ref, rows, 0.05).setting == "z"
    assert tradeoffs.recommend(ref, rows, 0.01).setting == "reference"     # v: 2 %, noise
    assert tradeoffs.recommend(ref, rows, 0.01, min_speedup=1.0).setting == "v"
    assert tradeoffs.recommend(ref, rows, 0.5).setting == "y"
