"""The rest of the package against real runs on small meshes: Ctrl-C and the library's
interrupt, the progress bar, branches, spectra, compare, meshes, groups, the model's
symmetry-adapted blocks, collect with Parquet, pyvista."""

import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

import memstab

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "scenes"


def tiny_disc(divisions=4, branches=False):
    doc = memstab.Scene.load(SCENES / "disc_upward.toml").to_dict()
    if not branches:
        doc["analysis"].pop("branches")
    return memstab.Scene.from_dict(doc, "disc_upward.toml").with_(mesh__divisions=divisions)


def python(script: str, env=None, **kw):
    """Runs `script` in a fresh interpreter (the library's test hooks are read once per
    process, and a signal must not reach pytest)."""
    return subprocess.Popen(
        [sys.executable, "-c", textwrap.dedent(script)],
        cwd=ROOT,
        env={**os.environ, **(env or {})},
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        **kw,
    )


# -- Ctrl-C -------------------------------------------------------------------------------


def test_the_library_interrupt_raises_keyboard_interrupt_with_the_path_written(tmp_path):
    # The library's hook requests the stop after the third accepted step, as a signal
    # arriving then would; a second run in the same process is not stopped by it.
    out = tmp_path / "cut"
    script = f"""
        import sys
        sys.path.insert(0, {str(Path(__file__).parent)!r})
        from test_api import tiny_disc
        import memstab
        try:
            memstab.run(tiny_disc(), out={str(out)!r}, progress=False)
            print("finished")
        except KeyboardInterrupt as e:
            print("KeyboardInterrupt:", e)
        again = memstab.run(tiny_disc(3), progress=False)
        print("then:", again.stop)
    """
    p = python(script, env={"MEMSTAB_INTERRUPT_AFTER_STEPS": "3"})
    stdout, stderr = p.communicate(timeout=300)
    assert p.returncode == 0, stderr
    lines = stdout.splitlines()
    assert lines[0].startswith("KeyboardInterrupt: interrupted: the path so far is written"), stdout
    assert lines[1].startswith("then: the control parameter left"), stdout
    rows = (out / "path.csv").read_text().splitlines()
    assert 1 + 3 <= len(rows) <= 1 + 5, rows  # the header, the start, about three steps
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["stop"] == "interrupted", manifest["stop"]


def test_ctrl_c_stops_a_run_promptly_and_raises_keyboard_interrupt(tmp_path):
    # The balloon at frequency 8 follows 400 steps past its pressure maximum and minimum;
    # SIGINT after its first points must end it within a few seconds.
    out = tmp_path / "balloon"
    script = f"""
        import sys, time
        import memstab
        scene = memstab.Scene.load("scenes/balloon.toml")
        said = []
        def tick(points, fraction, message):
            # Updates coming faster than the binding's 50 ms poll reach it merged (the
            # latest only), so the second point may be seen as a later one.
            if points >= 2 and not said:
                said.append(points)
                print("running", flush=True)
        try:
            memstab.run(scene, out={str(out)!r}, progress=tick)
            print("finished", flush=True)
        except KeyboardInterrupt as e:
            print("KeyboardInterrupt:", e, flush=True)
    """
    p = python(script)
    assert p.stdout.readline().strip() == "running", p.stderr.read()
    sent = time.perf_counter()
    p.send_signal(signal.SIGINT)
    stdout, stderr = p.communicate(timeout=60)
    seconds = time.perf_counter() - sent
    assert p.returncode == 0, stderr
    assert stdout.startswith("KeyboardInterrupt: interrupted: the path so far is written"), stdout
    assert seconds < 10, seconds
    rows = (out / "path.csv").read_text().splitlines()
    assert 3 <= len(rows) < 100, len(rows)
    assert json.loads((out / "manifest.json").read_text())["stop"] == "interrupted"


def test_a_spectrum_and_a_comparison_stop_at_the_library_interrupt(tmp_path):
    # The library's hooks request the stop after the first block of a spectrum, and after
    # the fifth sample of a comparison's linear-buckling sweeps.
    run = memstab.run(tiny_disc(3), out=tmp_path / "disc", progress=False)
    script = f"""
        import sys
        sys.path.insert(0, {str(Path(__file__).parent)!r})
        from test_api import tiny_disc
        import memstab
        from pathlib import Path
        result = memstab.Result(Path({str(run.dir)!r}), "", None, tiny_disc(3))
        try:
            result.spectrum(2)
            print("spectrum finished")
        except KeyboardInterrupt as e:
            print("KeyboardInterrupt:", e)
        print("then:", result.spectrum(2).attrs["index"])
        scene = memstab.Scene.load("scenes/ponding.toml").with_(
            {{"mesh.divisions": 3, "parameters.rho.max": 10.5, "analysis.samples": 40}}
        )
        try:
            memstab.compare(scene, ["C7v", "C1v"], progress=False)
            print("compare finished")
        except KeyboardInterrupt as e:
            print("KeyboardInterrupt:", e)
    """
    p = python(
        script,
        env={"MEMSTAB_INTERRUPT_AFTER_BLOCKS": "1", "MEMSTAB_INTERRUPT_AFTER_STEPS": "5"},
    )
    stdout, stderr = p.communicate(timeout=300)
    assert p.returncode == 0, stderr
    lines = stdout.splitlines()
    assert lines[0] == "KeyboardInterrupt: interrupted: stopped between the tangent's blocks", stdout
    row = run.path[run.path["step"] == 2].iloc[0]
    assert lines[1] == f"then: {int(row['index'])}", stdout
    assert lines[2].startswith("KeyboardInterrupt: interrupted"), stdout


# -- progress --------------------------------------------------------------------------


def test_a_run_shows_the_command_lines_progress_in_tqdm(monkeypatch, capsys):
    pytest.importorskip("tqdm")
    result = memstab.run(tiny_disc(3), progress=True)
    err = capsys.readouterr().err
    points = result.summary["points"]
    # The bar's last message: the control, its range, the points (as the command line's).
    assert "h = " in err and f"{points} points" in err, err[-500:]
    memstab.run(tiny_disc(3), progress=False)
    assert capsys.readouterr().err == ""
    memstab.run(tiny_disc(3))  # stderr is not a terminal here: no bar, as on the command line
    assert capsys.readouterr().err == ""


def test_the_progress_bar_follows_the_control(monkeypatch):
    updates = []

    class Recorder:
        def __init__(self, total=None, desc=None, leave=True, bar_format=None):
            self.total, self.n, self.closed = total, 0, False
            updates.append(self)
            self.seen = []

        def set_postfix_str(self, s, refresh=True):
            self.postfix = s

        def refresh(self):
            self.seen.append((self.n, self.postfix))

        def close(self):
            self.closed = True

    monkeypatch.setattr(memstab, "_tqdm", lambda: Recorder)
    result = memstab.run(tiny_disc(3), progress=True)
    (bar,) = updates
    assert bar.total == memstab._Bar.TICKS and bar.closed
    assert len(bar.seen) == result.summary["points"]
    ticks = [n for n, _ in bar.seen]
    h = result.path["h"].to_numpy()
    h_range = memstab.Scene.load(SCENES / "disc_upward.toml").to_dict()["parameters"]["h"]
    lo, hi = h_range["min"], h_range["max"]
    expected = np.round(np.clip((h - lo) / (hi - lo), 0, 1) * memstab._Bar.TICKS)
    assert ticks == list(expected), (ticks, list(expected))
    assert bar.seen[-1][1].endswith(f"{len(h)} points")
    assert bar.postfix.startswith("stopped: the control parameter left")


# -- branches and spectra ----------------------------------------------------------------


@pytest.fixture(scope="module")
def branched(tmp_path_factory):
    out = tmp_path_factory.mktemp("branched") / "disc"
    return memstab.run(tiny_disc(4, branches=True).with_({"analysis.branches.steps": 6}), out=out)


def test_the_branches_of_a_run(branched):
    table = branched.branches
    assert len(table) >= 2, table
    files = json.loads((branched.dir / "branches.json").read_text())["branches"]
    assert list(table["id"]) == [b["id"] for b in files]
    for n in range(1, len(table) + 1):
        b = branched.branch(n)
        row = table.iloc[n - 1]
        assert b.dir == branched.dir / row["directory"]
        path = b.path
        assert len(path) == row["points"], (len(path), row["points"])
        assert list(path.columns[:3]) == ["step", "arclength", "h"]
        assert len(b.critical) == row["critical"]
        assert b.info["irrep"] == row["irrep"]
    # A branch starts at the critical point it leaves: the path's, at its level.
    nodes = json.loads((branched.dir / "branches.json").read_text())["nodes"]
    for n in range(1, len(table) + 1):
        b = branched.branch(n)
        (start,) = [x for x in nodes if x["id"] == b.info["from"]]
        assert start["type"] == "critical" and start["on"] == "path"
        assert b.path["h"].iloc[0] == pytest.approx(start["parameters"]["h"], rel=1e-12)
        assert start["parameters"]["h"] in list(branched.critical["value"])
    with pytest.raises(KeyError, match="numbered from 1"):
        branched.branch(len(table) + 1)


def test_the_spectrum_at_a_path_point_and_at_a_critical_point(branched):
    path = branched.path
    spectrum = branched.spectrum(0)
    assert list(spectrum["irrep"])[:2] == ["A1", "A2"]
    group = memstab.group("C7v")
    assert list(spectrum["irrep"]) == list(group.irreps["name"])
    assert list(spectrum["dim"]) == list(group.irreps["dim"])
    # The index Σ d·neg is the run's at every point: path.csv's index_<irrep> columns.
    for step in [0, int(path["step"].iloc[-1])]:
        s = branched.spectrum(step)
        row = path[path["step"] == step].iloc[0]
        assert s.attrs["index"] == row["index"]
        for _, b in s.iterrows():
            assert b["negative"] == row[f"index_{b['irrep']}"], (step, b["irrep"])
        assert s.attrs["parameters"]["h"] == row["h"]
    # At a critical point, the block of its irrep has an eigenvalue near zero.
    critical = branched.critical
    for n, (_, c) in enumerate(critical.iterrows(), start=1):
        s = branched.spectrum(critical=n).set_index("irrep")
        lowest = np.abs(s.loc[c["irrep"], "lowest"]).min()
        others = [np.abs(v).min() for i, v in s["lowest"].items() if i != c["irrep"] and len(v)]
        assert lowest < 1e-4 and lowest < 1e-2 * min(others), (n, c["irrep"], lowest, others)
    with pytest.raises(memstab.MemstabError, match="path points"):
        branched.spectrum(10_000)
    with pytest.raises(TypeError):
        branched.spectrum()


# -- the model's blocks ----------------------------------------------------------------


def test_the_adapted_blocks_hold_the_tangents_eigenvalues():
    scene = memstab.Scene.load(SCENES / "disc_upward.toml").with_(mesh__divisions=2)
    model = scene.model()
    u, p = model.start()
    p = p + 1.0  # a loaded state: the tangent is not the flat one's
    k = model.tangent(u, p).toarray()
    bases = model.adapted_bases()
    irreps = model.irreps()
    assert list(irreps["irrep"]) == list(bases) == list(memstab.group("C7v").irreps["name"])
    # The partners' copies make up all unknowns: Σ d·m = n.
    assert (irreps["dim"] * irreps["size"]).sum() == model.unknowns
    blocks = model.blocks(u, p)
    eig = []
    for (_, row), (name, block) in zip(irreps.iterrows(), blocks.items()):
        b = bases[name]
        assert np.allclose((b.T @ b).toarray(), np.eye(b.shape[1]), atol=1e-12)
        values = np.linalg.eigvalsh(block.toarray())
        eig += list(values) * (1 if row["complex"] else row["dim"])
    assert np.allclose(sorted(eig), np.linalg.eigvalsh(k), atol=1e-9 * np.abs(k).max())
    # The fixed-point basis spans the trivial block's space, and F lies in it.
    f = model.fixed_point_basis()
    a1 = bases["A1"]
    assert f.shape == a1.shape
    assert np.allclose((f @ f.T).toarray(), (a1 @ a1.T).toarray(), atol=1e-12)
    residual = model.residual(u + f @ np.ones(f.shape[1]) * 1e-3, p)
    assert np.linalg.norm(residual - f @ (f.T @ residual)) < 1e-10 * np.linalg.norm(residual)


# -- compare, mesh, group --------------------------------------------------------------


def test_compare_splits_the_double_point_on_the_lower_mesh():
    scene = memstab.Scene.load(SCENES / "ponding.toml").with_(
        {"mesh.sectors": 8, "mesh.divisions": 6, "parameters.rho.max": 10.5, "analysis.samples": 40}
    )
    c = memstab.compare(scene, ["C8v", "C2v"], progress=False)
    assert list(c.meshes["label"]) == ["C8v", "C2v"]
    assert list(c.meshes["group"]) == ["C8v", "C2v"]
    m1 = c.rungs[c.rungs["m"] == 1]
    on8 = m1[m1["mesh"] == "C8v"].iloc[0]
    on2 = m1[m1["mesh"] == "C2v"].iloc[0]
    assert on8["irreps"] == "E1" and len(on8["values"]) == 1
    assert sorted(on2["irreps"].split(" + ")) == ["B1", "B2"] and len(on2["values"]) == 2
    assert on2["gap"] == pytest.approx(abs(on2["values"][1] - on2["values"][0]), rel=1e-9)
    assert 0 < on2["gap"] < 1e-2 * on8["values"][0]
    assert len(c.critical[c.critical["label"] == "C8v"]) == c.meshes["critical"].iloc[0]
    with pytest.raises(memstab.MemstabError, match=r"with mesh 'Q7': 'mesh.group': group 'Q7'"):
        memstab.compare(scene, ["C8v", "Q7"], progress=False)


def test_mesh_and_group():
    m, name = memstab.mesh("disc", sectors=8, divisions=3, group="C4v")
    assert name == "C4v"
    assert len(m.cells_dict["triangle"]) == 8 * 3 * 3
    orbits = m.point_data["node_orbit"]
    # C4v (order 8) acts on the nodes: every orbit but the centre's has 4 or 8 nodes.
    sizes = np.bincount(orbits.astype(int))
    assert sorted(set(sizes)) == [1, 4, 8], sorted(set(sizes))
    ico, name = memstab.mesh("icosphere", frequency=2)
    assert name == "Ih" and len(ico.points) == 10 * 4 + 2
    with pytest.raises(memstab.MemstabError, match="mesh.sectors"):
        memstab.mesh("disc", sectors=0)
    with pytest.raises(memstab.MemstabError, match="mesh.frequency"):
        memstab.mesh("disc", frequency=3)

    g = memstab.group("C4v")
    assert g.order == 8 and list(g.irreps["name"]) == ["A1", "A2", "B1", "B2", "E1"]
    assert list(g.irreps["dim"]) == [1, 1, 1, 1, 2]
    chi = g.characters
    # The identity's column holds the dimensions; the rows are orthogonal.
    assert list(chi.iloc[:, 0]) == [1, 1, 1, 1, 2]
    sizes = np.array([len(c) for c in g.classes])
    gram = (chi.to_numpy() * sizes) @ chi.to_numpy().T / g.order
    assert np.allclose(gram, np.eye(5))
    ih = memstab.group("Ih")
    assert ih.order == 120 and (ih.irreps["dim"] ** 2).sum() == 120
    with pytest.raises(memstab.MemstabError, match="D4"):
        memstab.group("D4")


# -- collect ---------------------------------------------------------------------------


def test_collect_returns_frames_and_writes_parquet(tmp_path):
    sweep = tmp_path / "sweep.toml"
    sweep.write_text(
        textwrap.dedent(
            f"""
            [sweep]
            name = "k"
            scene = "{(SCENES / 'disc_upward.toml').as_posix()}"
            [grid]
            "material.k" = [0.0, 0.1]
            "mesh.divisions" = [3]
            """
        )
    )
    binary = ROOT / "target" / "release" / "memstab"
    if not binary.is_file():
        pytest.skip("needs the memstab binary (cargo build --release)")
    done = subprocess.run(
        [binary, "sweep", sweep, "--out", tmp_path / "k", "--quiet"],
        capture_output=True, text=True,
    )
    if done.returncode != 0:
        pytest.skip(f"sweep: {done.stderr}")
    got = memstab.collect(tmp_path / "k")
    assert list(got.runs["status"]) == ["finished", "finished"]
    import pandas as pd

    csv = pd.read_csv(tmp_path / "k" / "collected.csv")
    assert len(got.points) == len(csv) > 0
    try:
        import pyarrow  # noqa: F401
    except ImportError:
        assert not (tmp_path / "k" / "collected.parquet").exists()
        return
    back = pd.read_parquet(tmp_path / "k" / "collected.parquet")
    assert back.shape == got.points.shape
    assert np.allclose(back["value"], csv["value"])


# -- pyvista ---------------------------------------------------------------------------


def test_a_state_as_a_pyvista_mesh(branched):
    pv = pytest.importorskip("pyvista")
    m = branched.state(0, pyvista=True)
    assert isinstance(m, pv.DataSet)
    meshio_state = branched.state(0)
    assert np.allclose(m.points, meshio_state.points)
    assert np.allclose(m.point_data["displacement"], meshio_state.point_data["displacement"])
    mode = branched.critical_state(1, pyvista=True)
    assert "critical_mode" in mode.point_data


# -- the model in another continuation package -----------------------------------------


def test_bice_finds_the_balloons_pressure_maximum_where_memstab_does():
    pytest.importorskip("bice")
    done = subprocess.run(
        [sys.executable, ROOT / "python" / "examples" / "bice_balloon.py"],
        cwd=ROOT, capture_output=True, text=True, timeout=600,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    assert "pressure maximum p R/(mu H): memstab 1.37" in done.stdout, done.stdout
