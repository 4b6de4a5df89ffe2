"""Times the kernel's f64 overdamped step through `host-demo run` against the NumPy +
pygrpy peer (overdamped_numpy.py) in one run, after checking that both give the same
trajectory.

    python3 bench/peer/compare.py [--demo target/release/host-demo] [--scene S] [--rounds 3]
    python3 bench/peer/compare.py --demo target/release/host-demo --demo target-v3/release/host-demo

With several `--demo` binaries (the default build and the fast x86-64-v3 build), each is
checked to write a byte-identical trajectory and timed against the same peer run.

1. Agreement: the scene cut to 20 steps with a frame every step is run through
   `host-demo run`; the peer starts from its first frame and must stay within 1e-9 of
   every frame (both solve the bonds to a relative error of 1e-12; only the Newton
   iterates differ).
2. Speed: `host-demo run` on the full scene (its run loop: step, observables, frames, as
   `summary.json` times it; process wall time printed too) and the peer for `--peer-steps`
   steps, alternately, `--rounds` times; the best of each is compared.

3. Fraction of the peak: where a binary's target directory holds `examples/peak` (built
   by `cargo build --release --example peak`, with the same config as the binary), it
   runs once a round beside the timings, and its best f64 rate is the peak the step's
   rate is read against. The peak is measured in the same minutes as the step because
   on a shared VM both move together (docs/BENCHMARKS.md: the vCPU's physical core is
   sometimes shared, which halves both). The step's rate is `--flops` (floating-point
   operations a step, counted by stage from the code for the 25-bead helix at its 3.3
   chord iterations a step: docs/BENCHMARKS.md) over the best run-loop time.

Needs numpy and pygrpy (`pip install numpy pygrpy`). Prints a table and the ratio;
with HYDRORATTLE_BENCH_MACHINE set, appends them to bench/results/helix25.csv
(bench/record.py).
"""

import argparse
import json
import pathlib
import re
import subprocess
import sys
import tempfile
import time
import tomllib

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from overdamped_numpy import OverdampedChain, read_xyz_frames  # noqa: E402

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent.parent))
import record  # noqa: E402

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parent.parent


def toml_text(scene, **changes):
    """The scene file with `[integrator] duration` / `[output] every` replaced."""
    out, section = [], None
    for line in scene.splitlines():
        s = line.strip()
        if s.startswith("["):
            section = s
        key = s.split("=")[0].strip()
        if section == "[integrator]" and key == "duration" and "duration" in changes:
            line = f"duration = {changes['duration']!r}"
        if section == "[output]" and key == "every" and "every" in changes:
            line = f"every = {changes['every']}"
        out.append(line)
    return "\n".join(out) + "\n"


def demo_run(demo, scene_path, out, threads=None):
    cmd = [str(demo), "run", str(scene_path), "--out", str(out)]
    if threads is not None:
        cmd += ["--threads", str(threads)]
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - t0
    summary = json.loads((pathlib.Path(out) / "summary.json").read_text())
    return summary, wall


def peak_of(demo):
    """The `peak` example beside a host-demo binary (same target directory), or None."""
    exe = pathlib.Path(demo).resolve().parent / "examples" / "peak"
    return exe if exe.is_file() else None


def peak_rate(exe):
    """The f64 GFLOP/s one run of the `peak` example prints."""
    out = subprocess.run([str(exe)], check=True, capture_output=True, text=True).stdout
    return float(re.search(r"f64 ([0-9.]+) GFLOP/s", out).group(1))


def peer_from(frame, cfg):
    _, pos, radius, mass = frame
    g = np.array(cfg["gravity"]["acceleration"], dtype=float)
    dhat = cfg["helix"]["dhat"]
    length = dhat * (radius[:-1] + radius[1:])
    weight = mass[:, None] * g[None, :]  # fluid density 0 in this scene: (rho - 0) V g
    integ = cfg["integrator"]
    return OverdampedChain(
        pos, radius, weight, length, integ["dt"],
        eta=cfg["fluid"]["viscosity"], tol=integ["tolerance"],
        max_iterations=integ["max_iterations"],
    )


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--demo", action="append", default=None,
                    help="a host-demo binary; give it more than once (the default build and "
                         "the fast x86-64-v3 one, docs/BENCHMARKS.md) to time each against the "
                         "same peer in one run (default target/release/host-demo)")
    ap.add_argument("--scene", default=str(HERE / "helix25.toml"))
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--peer-steps", type=int, default=500)
    ap.add_argument("--threads", type=int, default=None, help="passed to host-demo run")
    ap.add_argument("--flops", type=float, default=66.9e3,
                    help="floating-point operations a step of the scene (default: the "
                         "25-bead helix's count, docs/BENCHMARKS.md)")
    args = ap.parse_args()
    rows = record.Recorder("helix25", " ".join(["python3", "bench/peer/compare.py", *sys.argv[1:]]))
    table = "against the NumPy + pygrpy peer, alternated"
    demos = args.demo or [str(ROOT / "target/release/host-demo")]
    text = pathlib.Path(args.scene).read_text()
    cfg = tomllib.loads(text)
    if cfg["fluid"].get("density", 0.0) != 0.0 or cfg["integrator"]["method"] != "overdamped":
        sys.exit("the peer covers overdamped scenes with fluid density 0")
    dt = cfg["integrator"]["dt"]
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        # 1. Agreement over 20 steps, and every binary's trajectory byte for byte.
        short = tmp / "short.toml"
        short.write_text(toml_text(text, duration=20 * dt, every=1))
        trajectories = []
        for k, demo in enumerate(demos):
            demo_run(demo, short, tmp / f"short{k}", args.threads)
            trajectories.append((tmp / f"short{k}" / "trajectory.xyz").read_bytes())
        if any(t != trajectories[0] for t in trajectories):
            sys.exit("the host-demo binaries' trajectories differ")
        if len(demos) > 1:
            print(f"{len(demos)} binaries: trajectories byte-identical")
        frames = read_xyz_frames(tmp / "short0" / "trajectory.xyz")
        peer = peer_from(frames[0], cfg)
        worst = 0.0
        for k, frame in enumerate(frames[1:], start=1):
            peer.step()
            worst = max(worst, float(np.max(np.abs(peer.pos - frame[1]))))
        print(f"agreement: {len(frames) - 1} steps, largest position difference {worst:.2e}"
              f" (peer Newton iterations per step {peer.iterations / (len(frames) - 1):.2f})")
        if not worst <= 1e-9:
            sys.exit("the peer and the kernel disagree")
        # 2. Speed, alternating, best of `rounds`.
        demo_best = [np.inf] * len(demos)
        wall_best = [np.inf] * len(demos)
        peer_best = np.inf
        peaks = [peak_of(d) for d in demos]
        peak_best = [0.0] * len(demos)
        for _ in range(args.rounds):
            for k, demo in enumerate(demos):
                if peaks[k] is not None:
                    peak_best[k] = max(peak_best[k], peak_rate(peaks[k]))
                s, wall = demo_run(demo, args.scene, tmp / "full", args.threads)
                demo_best[k] = min(demo_best[k], s["wall_time_s"] / s["steps_done"])
                wall_best[k] = min(wall_best[k], wall / s["steps_done"])
            peer = peer_from(frames[0], cfg)
            t0 = time.perf_counter()
            for _ in range(args.peer_steps):
                peer.step()
            peer_best = min(peer_best, (time.perf_counter() - t0) / args.peer_steps)
        steps = s["steps_done"]
    print(f"NumPy + pygrpy peer ({args.peer_steps} steps)           {peer_best * 1e6:9.2f} us/step"
          f"  (mean Newton iterations {peer.iterations / args.peer_steps:.2f})")
    for k, demo in enumerate(demos):
        print(f"{demo}:")
        print(f"  host-demo run ({steps} steps, run loop)      {demo_best[k] * 1e6:9.2f} us/step"
              f"  (mean Newton iterations {s['mean_iterations']:.2f})")
        print(f"  host-demo run (process wall, with start-up) {wall_best[k] * 1e6:9.2f} us/step")
        print(f"  ratio peer / host-demo: {peer_best / demo_best[k]:.1f}x (run loop), "
              f"{peer_best / wall_best[k]:.1f}x (process wall)")
        rows.row(table, demo, "run loop", f"{demo_best[k] * 1e6:.2f} us")
        rows.row(table, demo, "peer", f"{peer_best * 1e6:.1f} us")
        rows.row(table, demo, "ratio", f"{peer_best / demo_best[k]:.1f}x")
        rate = args.flops / demo_best[k] / 1e9
        if peaks[k] is None:
            print(f"  {rate:.2f} GFLOP/s at {args.flops:.0f} flops a step (no examples/peak "
                  "beside this binary: no fraction of the peak)")
        else:
            print(f"  {rate:.2f} GFLOP/s at {args.flops:.0f} flops a step = "
                  f"{100 * rate / peak_best[k]:.1f} % of this build's f64 peak, "
                  f"{peak_best[k]:.2f} GFLOP/s (examples/peak, best of {args.rounds}, "
                  "same minutes)")
            rows.row(table, demo, "fraction of the f64 peak", f"{100 * rate / peak_best[k]:.1f} %")
    rows.finish()


if __name__ == "__main__":
    main()
