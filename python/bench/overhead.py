"""Overhead of the Python package over the Rust step (prints the numbers quoted in the
docs/PYTHON.md). Usage: python python/bench/overhead.py [path/to/host-demo]

* System.step(1000) at N = 25 (the Figure 1 (c) helix) against the CLI's own time loop
  on the same scene (summary.json's wall_time_s, frames every 100000 steps);
* one step(1) call at N = 2 (mostly call overhead) and at N = 25;
* a Python force callback per step;
* two threads stepping two systems against one after the other.
"""

import json
import pathlib
import subprocess
import sys
import tempfile
import threading
import time

import numpy as np

import hydrorattle as hr

ROOT = pathlib.Path(__file__).resolve().parents[2]
HOST_DEMO = pathlib.Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "target" / "release" / "host-demo"
SCENE = (ROOT / "host" / "scenes" / "figure1c.toml").read_text()
STEPS = 1000


def best(f, repeat=7):
    out = []
    for _ in range(repeat):
        t = time.perf_counter()
        f()
        out.append(time.perf_counter() - t)
    return min(out)


def scene_text(duration):
    text = SCENE.replace("duration = 400.0", f"duration = {duration}")
    return text.replace("every = 20 ", "every = 100000 ")


with tempfile.TemporaryDirectory() as d:
    path = pathlib.Path(d) / "c.toml"
    path.write_text(scene_text(STEPS * 0.1))
    rust = []
    for k in range(7):
        subprocess.run([str(HOST_DEMO), "run", str(path), "--out", f"{d}/o{k}"], check=True, capture_output=True)
        rust.append(json.loads((pathlib.Path(d) / f"o{k}" / "summary.json").read_text())["wall_time_s"])
    rust = min(rust)
    py = best(lambda: hr.System.from_scene(path).step(STEPS))
    build = best(lambda: hr.System.from_scene(path))
    py -= build
print(f"N=25 Figure 1 (c), {STEPS} steps: CLI time loop {rust * 1e3:.1f} ms, System.step({STEPS}) {py * 1e3:.1f} ms "
      f"(ratio {py / rust:.3f})")

s = hr.System.from_scene_text(scene_text(1.0), "c")
per = best(lambda: [s.step(1) for _ in range(200)]) / 200
many = best(lambda: s.step(200)) / 200
print(f"N=25: step(1) call {per * 1e6:.1f} us, step(200)/200 {many * 1e6:.1f} us per step: "
      f"call overhead {(per - many) * 1e6:.2f} us")
zero = lambda p: np.zeros_like(p)  # noqa: E731
with_force = best(lambda: s.step(200, force=zero)) / 200
print(f"N=25 overdamped2 (2 force evaluations per step): step with a Python force {with_force * 1e6:.1f} us, "
      f"callback cost {(with_force - many) / 2 * 1e6:.2f} us per evaluation")

d2 = hr.System([[0, 0, 0], [3, 0, 0]], 1.0, 4.5, bonds=[[0, 1]], dt=0.01)
per2 = best(lambda: [d2.step(1) for _ in range(10000)]) / 10000
many2 = best(lambda: d2.step(10000)) / 10000
print(f"N=2 dimer: step(1) call {per2 * 1e6:.2f} us, in-Rust step {many2 * 1e6:.2f} us: call overhead {(per2 - many2) * 1e6:.2f} us")

a = hr.System.from_scene_text(scene_text(1.0), "a")
b = hr.System.from_scene_text(scene_text(1.0), "b")
n = 2000
serial = best(lambda: (a.step(n), b.step(n)), 3)


def parallel():
    ts = [threading.Thread(target=x.step, args=(n,)) for x in (a, b)]
    for t in ts:
        t.start()
    for t in ts:
        t.join()


par = best(parallel, 3)
cpu0, wall0 = time.process_time(), time.perf_counter()
parallel()
cpu, wall = time.process_time() - cpu0, time.perf_counter() - wall0
print(f"two systems x {n} steps: one after the other {serial:.3f} s, two threads {par:.3f} s: speed-up {serial / par:.2f}; "
      f"CPU time / wall time of the threaded run {cpu / wall:.2f} (above 1 only if both threads ran at once)")
