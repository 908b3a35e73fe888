"""Fuzzed bad input (issue 11, item 4): a generated corpus of malformed scenes, each run
in-process through ``taichi-dem check`` (and a subset through ``taichi-dem run``).

Every case must exit 2 with one message naming the scene file and the key the generator broke
(or, for a file that is not TOML, the line), never a Python exception (a traceback from the
command line), never more than a few seconds. ``check`` must not start the Taichi runtime.
The corpus is seeded (``scene_fuzz.py``, stdlib ``random``): the same cases every run. About a
quarter of it (category "schema") is drawn from ``taichi-dem schema``: each key's type, range,
unit pattern, choices and required keys give its breakages, so a key is fuzzed the day it is
declared. Offline, ``python tests/fuzz/scene_fuzz.py --cases 10000 --seed N`` tries many more
(``--category schema`` only those) and counts tracebacks, hangs and exit-0 cases.
"""
import collections
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
import scene_fuzz as sf  # noqa: E402

SEED = 20260
CHECK_CASES = 550          # run through `check` (about 150 drawn from the schema)
RUN_PER_CATEGORY = 3       # the first cases of each category also run through `run`
LIMIT_S = 5.0              # per case (most take a few milliseconds)

BASES = sf.base_scenes()
CORPUS = sf.Fuzzer(BASES).corpus(CHECK_CASES, SEED)
# scenes whose keys are each valid but cannot work together (issue 33 item 7)
INCONSISTENT = sf.Fuzzer(BASES).inconsistent_cases(16, SEED)
RUN_CASES = [c for cat in sf.CATEGORIES
             for c in [x for x in CORPUS if x.category == cat][:RUN_PER_CATEGORY]]


def _report(case, outcome) -> str:
    return (f"{case.ident}: {'; '.join(outcome.problems)}\n"
            f"expected key: {' or '.join(case.expect_keys) or '-'}; fragments: "
            f"{case.expect_fragments}\nmessage: {outcome.message.strip()[:600]}")


@pytest.mark.parametrize("base", BASES, ids=[b.name for b in BASES])
def test_base_scenes_are_valid(base, tmp_path):
    """The corpus starts from valid scenes: as written, and as the fuzzer's TOML writer
    writes them back."""
    from taichi_dem.scene.loader import load_scene
    for name, text in (("original", base.text), ("rewritten", sf.dumps(base.doc))):
        case = sf.Case("valid", "valid", base.name, text.encode(), files=base.files)
        load_scene(sf.write_case(case, tmp_path / name))


@pytest.mark.parametrize("case", CORPUS, ids=[c.ident for c in CORPUS])
def test_check_refuses(case, tmp_path, no_taichi_runtime):
    o = sf.run_case(case, tmp_path, "check", LIMIT_S)
    assert not o.problems, _report(case, o)
    assert o.seconds < LIMIT_S


@pytest.mark.parametrize("case", INCONSISTENT, ids=[c.ident for c in INCONSISTENT])
def test_check_refuses_what_cannot_work_together(case, tmp_path, no_taichi_runtime):
    """A frame interval between samples (not a whole multiple of the output interval), a
    fill or factory region wholly behind a wall (the region blamed), a flipped wall normal
    (the normal blamed, not the fill's count), a results path that cannot be written: each
    exits 2 naming the key. (An output interval past end_time is valid: CONTRACT.md.)"""
    o = sf.run_case(case, tmp_path, "check", LIMIT_S)
    assert not o.problems, _report(case, o)


def test_the_inconsistent_cases_cover_every_kind():
    kinds = collections.Counter(c.ident.split("/")[-1].split()[-1] for c in INCONSISTENT)
    assert len(INCONSISTENT) == 16
    for words in ("between samples", "under a file", "flipped", "region behind"):
        assert any(words in c.ident for c in INCONSISTENT), (words, kinds)


def test_check_notes_a_temperature_without_thermal(tmp_path, capsys):
    """A temperature in a scene without [thermal] is not refused (CONTRACT.md's example has
    them) but named as ignored."""
    from taichi_dem.app.cli import main
    base = next(b for b in BASES if b.name == "contract_scene")
    path = sf.write_case(sf.Case("t", "t", base.name, base.text.encode(), files=base.files),
                         tmp_path)
    assert main(["check", str(path)]) == 0
    err = capsys.readouterr().err
    assert "particles[0].temperature: ignored" in err and "walls[0].temperature: ignored" in err


@pytest.mark.parametrize("case", RUN_CASES, ids=[c.ident for c in RUN_CASES])
def test_run_refuses(case, tmp_path):
    o = sf.run_case(case, tmp_path, "run", LIMIT_S)
    assert not o.problems, _report(case, o)
    # nothing was simulated, nothing written
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


def test_corpus_covers_every_category():
    counts = collections.Counter(c.category for c in CORPUS)
    assert set(counts) == set(sf.CATEGORIES), counts
    assert min(counts.values()) >= 3, counts
    assert len({c.ident for c in CORPUS}) == len(CORPUS)
    # every key-level case says which key; every file-level case which line or encoding
    for c in CORPUS:
        assert c.expect_keys or c.expect_fragments, c.ident
        assert all(c.expect_keys), c.ident


def test_corpus_is_deterministic():
    again = sf.Fuzzer(sf.base_scenes()).corpus(40, SEED)
    assert [(c.ident, c.text, c.expect_keys, c.files) for c in again] == \
        [(c.ident, c.text, c.expect_keys, c.files) for c in CORPUS[:40]]


def test_the_judge_is_not_vacuous(tmp_path, no_taichi_runtime):
    """A valid scene, a wrong expected key and a wrong expected line are all reported."""
    base = next(b for b in BASES if b.name == "loader_base")
    valid = sf.Case("valid", "valid", base.name, base.text.encode(), expect_keys=("domain",))
    o = sf.run_case(valid, tmp_path / "valid", "check", LIMIT_S)
    assert any("exit status 0" in p for p in o.problems), o.problems
    broken = next(c for c in CORPUS if c.category == "bad_number")
    wrong = sf.Case("wrong", broken.category, broken.base, broken.text,
                    expect_keys=("output.no_such_key",), files=broken.files)
    o = sf.run_case(wrong, tmp_path / "wrong", "check", LIMIT_S)
    assert any("names the key" in p for p in o.problems), o.problems
    cut = next(c for c in CORPUS if c.category == "truncated")
    line = int(cut.expect_fragments[1].split()[1])
    wrong_line = sf.Case("line", cut.category, cut.base, cut.text, files=cut.files,
                         expect_fragments=("TOML syntax error", f"line {line + 1}"))
    o = sf.run_case(wrong_line, tmp_path / "line", "check", LIMIT_S)
    assert any(f"line {line + 1}" in p for p in o.problems), o.problems


# The bugs the fuzzer found, pinned: (what, edit of demos/small_drum.toml, expected key).
# Each raised a Python exception (a traceback from the command line) or hung before the fix.
DRUM = (sf.ROOT / "demos" / "small_drum.toml").read_text()
REGRESSIONS = [
    ("builder count NaN (ValueError)", ("flights = 4", "flights = nan"), "bodies[0].mesh.flights"),
    ("builder count inf (OverflowError)", ("flights = 4", "flights = inf"),
     "bodies[0].mesh.flights"),
    ("builder length '1e999 m' (inf accepted)", ("radius = 0.1,", 'radius = "1e999 m",'),
     "bodies[0].mesh.radius"),
    ("builder angle '1e999 deg' (math domain error)",
     ("flight_height = 0.02", 'flight_height = 0.02, flight_phase_deg = "1e999 deg"'),
     "bodies[0].mesh.flight_phase_deg"),
    ("1e8 polygon sides (minutes, then MemoryError)",
     ("flights = 4,", "flights = 4, segments = 100000000,"),
     "bodies[0].mesh.segments"),
    ("1e7 flights (MemoryError)", ("flights = 4", "flights = 10000000"), "bodies[0].mesh.flights"),
    ("a 900 m drum of 10,000 sides (MemoryError)",
     ("length = 0.04,", "length = 900.0, segments = 10000,"),
     "bodies[0].mesh"),
    ("1e15 particles (MemoryError in the placement)", ("count = 400", "count = 1000000000000000"),
     "particles[0].count"),
    ("a sphere larger than its region (placement: count)", ("radius = 0.004", "radius = 4.0"),
     "particles[0].radius"),
    ("negative seed (numpy ValueError)", ("seed = 1", "seed = -1"), "simulation.seed"),
    ("velocity 1e300 m/s (ZeroDivisionError: dt = 0)",
     ("count = 400", "count = 400\nvelocity = [1e300, 0, 0]"), "particles[0].velocity[0]"),
    ("density 1e-300 (ZeroDivisionError)", ("density = 2500.0", "density = 1e-300"),
     "materials.glass.density"),
    ("Young's modulus 1e300 (OverflowError)", ("youngs_modulus = 5.0e7", "youngs_modulus = 1e300"),
     "materials.glass.youngs_modulus"),
    ("radius 1e-300 m (the placement never ends)", ("radius = 0.004", "radius = 1e-300"),
     "particles[0].radius"),
    ("a domain 1e-12 m across (a confusing message about the first region)",
     ("max = [0.05, 0.11, 0.11]", "max = [-0.009999999999, -0.109999999999, -0.109999999999]"),
     "domain.max"),
    ("max_particles beyond 32 bits (TypeError in Taichi's dense())",
     ("seed = 1", "seed = 1\nmax_particles = 1099511627776"), "simulation.max_particles"),
]


@pytest.mark.parametrize("what, edit, key", REGRESSIONS, ids=[r[0] for r in REGRESSIONS])
def test_found_bugs_stay_fixed(what, edit, key, tmp_path, no_taichi_runtime):
    old, new = edit
    assert DRUM.count(old) == 1, old
    case = sf.Case(what, "regression", "demo_small_drum", DRUM.replace(old, new).encode(),
                   expect_keys=(key,))
    o = sf.run_case(case, tmp_path, "check", LIMIT_S)
    assert not o.problems, _report(case, o)


def test_non_utf8_names_the_line_and_a_bom_is_accepted(tmp_path):
    """A Latin-1 degree sign is refused with its line; a UTF-8 byte-order mark and CRLF line
    ends (Windows editors) load."""
    from taichi_dem.scene.loader import load_scene
    from taichi_dem.errors import SceneError
    lines = DRUM.split("\n")
    i = next(k for k, ln in enumerate(lines) if '"20 rpm"' in ln)
    bad = "\n".join(lines).replace('"20 rpm"', '"20 rpm" # 120\u00b0/s').encode("latin-1")
    p = tmp_path / "latin1.toml"
    p.write_bytes(bad)
    with pytest.raises(SceneError) as e:
        load_scene(p)
    assert f"line {i + 1}," in e.value.reason and "0xb0" in e.value.reason
    p = tmp_path / "bom.toml"
    p.write_bytes(b"\xef\xbb\xbf" + DRUM.replace("\n", "\r\n").encode())
    scene = load_scene(p)
    assert scene.text == DRUM and scene.bodies[0].name == "drum"
