"""The package against the CLI: the same files from run_scene, the same bits from
System, one scene per method in f64 and f32; scene errors placed in their file."""

import json
import os
import pathlib
import subprocess

import numpy as np
import pytest

import hydrorattle as hr

ROOT = pathlib.Path(__file__).resolve().parents[2]
HOST_DEMO = pathlib.Path(os.environ.get("HYDRORATTLE_HOST_DEMO", ROOT / "target" / "release" / "host-demo"))

if not HOST_DEMO.exists():
    if os.environ.get("CI"):
        raise RuntimeError(f"{HOST_DEMO} missing: build it with cargo build --release -p host-demo")
    pytest.skip(f"{HOST_DEMO} not built", allow_module_level=True)

# dt and duration per method: the explicit ones within their stability limits.
METHODS = {
    "overdamped": (0.05, 2.0),
    "overdamped2": (0.05, 2.0),
    "rattle": (0.02, 0.8),
    "rattle-stable": (0.05, 2.0),
    "springs": (0.002, 0.08),
}


def scene(tmp_path, method, precision, extra=""):
    dt, duration = METHODS[method]
    text = f"""
[helix]
tails = 8
head_ratio = 1.5
dhat = 1.2

[integrator]
method = "{method}"
dt = {dt}
duration = {duration}
precision = "{precision}"

[output]
every = 7
{extra}
"""
    path = tmp_path / f"{method}-{precision}.toml"
    path.write_text(text)
    return path, round(duration / dt)


def cli_run(path, out):
    subprocess.run([str(HOST_DEMO), "run", str(path), "--out", str(out)], check=True,
                   capture_output=True)


def last_frame(out):
    run = hr.read_run(out)
    return run.time[-1], run.positions[-1], run.velocities[-1]


@pytest.mark.parametrize("precision", ["f64", "f32"])
@pytest.mark.parametrize("method", list(METHODS))
def test_system_steps_the_bits_of_the_cli(tmp_path, method, precision):
    path, steps = scene(tmp_path, method, precision)
    cli_run(path, tmp_path / "cli")
    t, pos, vel = last_frame(tmp_path / "cli")
    s = hr.System.from_scene(path)
    assert s.precision == precision
    s.step(steps)
    assert s.time == t
    assert np.array_equal(s.positions, pos)
    assert np.array_equal(s.velocities, vel)
    # The run yields the same bits in pieces.
    s2 = hr.System.from_scene(path)
    frames = list(s2.run(until=s.time, every=7))
    assert np.array_equal(frames[-1].positions, pos)
    run = hr.read_run(tmp_path / "cli")
    assert np.array_equal(np.array([f.positions for f in frames]), run.positions)


def test_thermal_system_steps_the_bits_of_the_cli(tmp_path):
    path, steps = scene(tmp_path, "overdamped", "f64", "\n[brownian]\ntemperature = 0.3\nseed = 11\n")
    cli_run(path, tmp_path / "cli")
    _, pos, _ = last_frame(tmp_path / "cli")
    s = hr.System.from_scene(path)
    s.step(steps)
    assert np.array_equal(s.positions, pos)


SUMMARY_WALL = ("wall_time_s", "steps_per_second")


def test_run_scene_writes_the_files_of_the_cli(tmp_path):
    path, _ = scene(tmp_path, "overdamped2", "f64")
    cli_run(path, tmp_path / "cli")
    summary = hr.run_scene(path, tmp_path / "py")
    # The run draws nothing: the CLI draws its pictures after it; the package writes
    # the run's data, byte for byte the CLI's.
    pictures = (".png", ".gif")
    names = sorted(p.name for p in (tmp_path / "cli").iterdir() if p.suffix not in pictures)
    assert names == sorted(p.name for p in (tmp_path / "py").iterdir())
    assert {"trajectory.xyz", "trajectory.gsd", "observables.csv", "scene.toml", "summary.json"} <= set(names)
    for name in names:
        a, b = (tmp_path / d / name for d in ("cli", "py"))
        if name == "summary.json":
            ja, jb = json.loads(a.read_text()), json.loads(b.read_text())
            for k in SUMMARY_WALL:
                ja.pop(k), jb.pop(k)
            assert ja == jb
        else:
            assert a.read_bytes() == b.read_bytes(), name
    assert summary["steps_done"] == summary["steps"] == 40
    run = hr.read_run(tmp_path / "py")
    assert run.positions.shape == (len(run.time), 9, 3)
    assert run.summary["outcome"] == summary["outcome"]
    assert run.species[0] == "head" and run.radii[0] == 1.5


def test_a_bad_scene_is_a_scene_error_with_file_and_line(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[fluid]\nviscosity = 1.0\n\n[integrator]\nmethod = \"leapfrog\"\ndt = 0.1\nduration = 1.0\n")
    for call in (hr.load_scene, hr.System.from_scene, lambda p: hr.run_scene(p, tmp_path / "o")):
        with pytest.raises(hr.SceneError) as e:
            call(bad)
        assert isinstance(e.value, ValueError)
        assert e.value.file == str(bad) and e.value.line == 5
    assert not (tmp_path / "o").exists()
    r = subprocess.run([str(HOST_DEMO), "run", str(bad), "--out", str(tmp_path / "o")], capture_output=True, text=True)
    assert r.returncode != 0 and f"{bad}:5:" in r.stderr


def test_load_scene_fills_the_defaults(tmp_path):
    path, _ = scene(tmp_path, "overdamped", "f32")
    s = hr.load_scene(path)
    assert len(s["particles"]) == 9 and len(s["bonds"]) == 8
    assert s["integrator"]["precision"] == "f32"
    assert s["fluid"]["viscosity"] == 1.0


def test_ase_atoms_when_ase_is_installed(tmp_path):
    pytest.importorskip("ase")
    path, _ = scene(tmp_path, "overdamped", "f64")
    hr.run_scene(path, tmp_path / "py")
    run = hr.read_run(tmp_path / "py")
    atoms = run.atoms()
    assert len(atoms) == len(run.time)
    assert np.array_equal(atoms[-1].positions, run.positions[-1])
