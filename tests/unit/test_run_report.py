"""The run report agrees with itself (issue 33 item 6): a run that stops between two regular
samples closes with a sample at its last instant, so the series, the last frame and the
summary describe the final state; every time-averaged figure names its window; each body has
one torque line."""
import re
import subprocess
import sys
from pathlib import Path

import h5py
import pytest

ROOT = Path(__file__).resolve().parents[2]


def _cli(*args, cwd=ROOT):
    return subprocess.run([sys.executable, "-m", "taichi_dem", *args], capture_output=True,
                          text=True, cwd=cwd, timeout=600)


def test_cooler_report_describes_one_instant(tmp_path):
    # 0.7 s: the regular samples fall every 4,167 steps (0.50004 s), so the last one is at
    # 0.5 s and the run's last 0.2 s would be missing from the series without the closing one
    r = _cli("run", "demos/paddle_cooler.toml", "--until", "0.7", "--quiet", "--out", str(tmp_path))
    assert r.returncode == 0, r.stderr
    out = r.stdout
    with h5py.File(tmp_path / "paddle_cooler.h5", "r") as f:
        t = f["series/time"][()]
        assert t[-1] == pytest.approx(0.7, abs=1.3e-4)
        frames = sorted(f["frames"], key=int)
        assert float(f["frames"][frames[-1]].attrs["time"]) == pytest.approx(t[-1])
        fed_series = float(f["series/factories/inlet/mass"][-1])
    # one torque line per body, with its window; none printed twice
    for body in ("shaft", "shell"):
        lines = [line for line in out.splitlines() if re.search(rf"\b{body}\b.*axial torque", line)]
        assert len(lines) == 1, out
        assert "mean over t = 0.5 - 0.7 s" in lines[0]
    assert "mean of the last" not in out and "second half" not in out
    # what the factory says it fed is what the mass balance (the final state) counts
    fed = float(re.search(r"factory 'inlet': ([0-9.e+-]+) kg fed by t = 0.7 s", out).group(1))
    balance = float(re.search(r"mass balance: \S+ initial \+ ([0-9.e+-]+) fed", out).group(1))
    assert fed == pytest.approx(balance, rel=1e-3)
    assert fed == pytest.approx(fed_series, rel=1e-3)
    assert "energy balance in 0.7 s" in out


def test_a_frame_interval_between_samples_is_refused(tmp_path):
    text = (ROOT / "demos/pile.toml").read_text()
    scene = tmp_path / "pile.toml"
    scene.write_text(text.replace("[output]", "[output]\nframe_interval = 0.03", 1))
    r = _cli("check", str(scene))
    assert r.returncode == 2
    assert "output.frame_interval" in r.stderr and "whole multiple" in r.stderr
    assert "Traceback" not in r.stderr


def test_summary_figures_carry_the_standard_error_of_their_mean():
    """error_words: blocking's standard error of the mean; for independent samples of standard
    deviation 2 it is 2 / sqrt(n) (n = 1024: 0.0625, within the blocking's own scatter of ~10 %
    at the level it settles on); none for a single sample."""
    import numpy as np
    from taichi_dem.app.summaries import error_words
    x = np.random.default_rng(3).normal(5.0, 2.0, 1024)
    se = float(error_words(x).split("+-")[1])
    assert se == pytest.approx(2.0 / 32.0, rel=0.25)
    assert float(error_words(x, 3.6).split("+-")[1]) == pytest.approx(3.6 * se, rel=0.02)
    assert error_words([1.0]) == "" and error_words([1.0, float("nan")]) == ""
