"""The Python package against real runs on small meshes: scenes loaded, changed and refused
with the command line's messages, runs read back as frames and meshes, the model's residual
and tangent checked against each other and against the run, the GIL released during a run."""

import json
import threading
import time
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

import memstab

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "scenes"


def tiny_disc(divisions=4):
    """The upward-loaded disc of the first paper, without its branches, on a coarse mesh."""
    doc = memstab.Scene.load(SCENES / "disc_upward.toml").to_dict()
    doc["analysis"].pop("branches")
    return memstab.Scene.from_dict(doc, "disc_upward.toml").with_(mesh__divisions=divisions)


def test_a_scene_loads_changes_and_refuses_bad_keys_with_the_cli_messages():
    scene = memstab.Scene.load(SCENES / "balloon.toml")
    assert scene.name == "balloon"
    assert scene.to_dict()["material"]["k"] == 0.1
    changed = scene.with_({"material.k": 0.05}, mesh__frequency=4)
    assert changed.to_dict()["material"]["k"] == 0.05
    assert changed.to_dict()["mesh"]["frequency"] == 4
    assert scene.to_dict()["material"]["k"] == 0.1, "with_ returns a copy"
    with pytest.raises(memstab.MemstabError, match=r"unknown key 'material.kk'"):
        scene.with_({"material.kk": 1.0})
    with pytest.raises(memstab.MemstabError, match=r"'material.k' must be >= 0, got -1"):
        scene.with_(material__k=-1.0)
    with pytest.raises(memstab.MemstabError, match=r"has 1 entries"):
        scene.with_({"effect[2].pressure": 1.0})
    with pytest.raises(memstab.MemstabError, match=r"nope.toml: cannot read the scene file"):
        memstab.Scene.load(SCENES / "nope.toml")
    message = str(pytest.raises(memstab.MemstabError, memstab.Scene.load, SCENES / "nope.toml").value)
    assert "\n" not in message


def test_a_run_is_read_back_as_frames_and_meshes(tmp_path):
    result = memstab.run(tiny_disc(), out=tmp_path / "disc")
    assert result.stop.startswith("the control parameter left")
    path = result.path
    assert list(path.columns[:3]) == ["step", "arclength", "h"]
    assert len(path) == result.summary["points"]
    critical = result.critical
    assert list(critical.columns[:6]) == ["kind", "irrep", "multiplicity", "isotropy", "m", "value"]
    files = json.loads((tmp_path / "disc" / "critical.json").read_text())
    assert len(critical) == len(files) > 0
    for (_, row), c in zip(critical.iterrows(), files):
        assert row["irrep"] == c["irrep"] and row["value"] == c["parameters"]["h"]
    e1 = critical[(critical["irrep"] == "E1") & (critical["m"] == 1)]
    assert len(e1) >= 1 and (e1["multiplicity"] == 2).all()
    # Each critical value lies between the path rows around it.
    for _, row in critical.iterrows():
        before = path[path["step"] == row["step"]]["h"].iloc[0]
        after = path[path["step"] == row["step"] + 1]["h"].iloc[0]
        assert min(before, after) - 1e-12 <= row["value"] <= max(before, after) + 1e-12

    assert 0 in result.states
    state = result.state(0)
    assert state.points.shape[1] == 3
    assert np.allclose(state.point_data["displacement"], 0.0)
    last = result.states[-1]
    moved = result.state(last)
    model = tiny_disc().model()
    u = np.zeros(model.unknowns)
    assert np.abs(moved.point_data["displacement"]).max() > 0.1
    with pytest.raises(KeyError, match="saved steps"):
        result.state(10_000)
    mode = result.critical_state(1).point_data["critical_mode"]
    assert abs(np.linalg.norm(mode) - 1.0) < 1e-9
    assert np.allclose(model.positions(u, model.start_values), state.points)


def test_a_run_in_a_temporary_directory_and_its_failure():
    result = memstab.run(tiny_disc(3))
    assert result.dir.is_dir() and (result.dir / "manifest.json").is_file()
    # The level far above the fold: the start does not converge (the command line's line).
    past = memstab.Scene.load(SCENES / "disc_fluid_below.toml").with_(
        {"parameters.h.start": 6.0, "parameters.h.max": 7.0, "mesh.divisions": 6}
    )
    with pytest.raises(memstab.MemstabError, match="no equilibrium near the start") as e:
        memstab.run(past)
    assert "\n" not in str(e.value)


def test_the_model_residual_and_tangent_agree_and_vanish_at_the_start():
    scene = memstab.Scene.load(SCENES / "demo.toml")
    model = scene.model()
    u, p = model.start()
    assert u.shape == (model.unknowns,) and list(model.parameters) == ["p"]
    f = model.residual(u, p)
    loads = model.loads(u, p)
    assert loads.shape == (model.unknowns, 1)
    assert np.linalg.norm(f) < 1e-8 * np.linalg.norm(loads), "the start is an equilibrium"
    k = model.tangent(u, p)
    assert sp.issparse(k) and k.shape == (model.unknowns, model.unknowns)
    assert abs(k - k.T).max() <= 1e-12 * abs(k).max(), "K is symmetric"
    # K v against a central difference of F, in a random direction.
    rng = np.random.default_rng(1)
    v = rng.standard_normal(model.unknowns)
    eps = 1e-6
    fd = (model.residual(u + eps * v, p) - model.residual(u - eps * v, p)) / (2 * eps)
    assert np.linalg.norm(fd - k @ v) < 1e-6 * np.linalg.norm(k @ v)
    # dF/dp against a difference in p.
    dp = (model.residual(u, p + eps) - model.residual(u, p - eps)) / (2 * eps)
    assert np.linalg.norm(dp - loads[:, 0]) < 1e-6 * np.linalg.norm(loads[:, 0])
    with pytest.raises(memstab.MemstabError, match="unknowns"):
        model.residual(u[:-1], p)


def test_a_run_releases_the_gil():
    # Held through the run, the GIL would let the main thread wake once, after it: one gap
    # as long as the run. Released, the main thread keeps waking every few milliseconds.
    scene = tiny_disc(24)
    done = threading.Event()
    out = {}

    def work():
        start = time.perf_counter()
        out["result"] = memstab.run(scene)
        out["seconds"] = time.perf_counter() - start
        done.set()

    thread = threading.Thread(target=work)
    gaps, last = [], time.perf_counter()
    thread.start()
    while not done.is_set():
        time.sleep(0.005)
        now = time.perf_counter()
        gaps.append(now - last)
        last = now
    thread.join()
    # Long enough to tell: many of the main thread's 5 ms sleeps fit into it.
    assert out["seconds"] > 20 * 0.005, out["seconds"]
    assert len(gaps) > 10 and max(gaps) < 0.5 * out["seconds"], (max(gaps), out["seconds"])
