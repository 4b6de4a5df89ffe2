"""Times the shipped free-space scenes (host/scenes/*.toml without a box or a wall)
under each explicit mobility path: the stored mobility (as shipped), its compact copy
(`compact_products = true`) and matrix-free (`matrix_free = true`), each a short run of
`host-demo run` (output as shipped), the CPU seconds of the child process (user +
system), best of REPS, at STEPS steps and at a fifth of them: the difference over the
steps between is the time a step, without the start (reading, checks, files). A scene
with a near field runs a tenth of the steps (its steps cost a hundred times more). A path the scene's method refuses is
recorded as refused. The choice `auto` makes for each scene is tested in
host/src/scene/free_cost_tests.rs (`auto_picks_dense_for_the_shipped_scenes`).

    python3 bench/free_scenes.py [HOST_DEMO [STEPS [REPS]]]    # 5000 steps, best of 3

HOST_DEMO defaults to target/release/host-demo (CARGO_TARGET_DIR honoured). With
HYDRORATTLE_BENCH_MACHINE set, rows go to bench/results/free_scenes.csv.
"""

import os
import pathlib
import re
import resource
import subprocess
import sys
import tempfile
import tomllib

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import record  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parent.parent
TABLE = ("shipped free-space scenes, CPU seconds of host-demo runs (best of the "
         "repetitions), by mobility path, one thread")
PATHS = {
    "dense": {},
    "compact": {"compact_products": "true"},
    "matrix-free": {"matrix_free": "true"},
}


def variant(text, dt, steps, keys):
    """The scene with `duration` set to `steps` steps and `keys` added to [integrator]."""
    text = re.sub(r"(?m)^duration\s*=.*$", f"duration = {dt * steps!r}", text)
    extra = "".join(f"{k} = {v}\n" for k, v in keys.items())
    return re.sub(r"(?m)^\[integrator\]\s*$", "[integrator]\n" + extra.rstrip("\n"), text)


def cpu_of(cmd):
    """Runs `cmd`; its CPU seconds (user + system) and exit status."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    used = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return used, done


def main(argv):
    target = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    binary = argv[1] if len(argv) > 1 else str(target / "release" / "host-demo")
    steps = int(argv[2]) if len(argv) > 2 else 5000
    reps = int(argv[3]) if len(argv) > 3 else 3
    rows = record.Recorder("free_scenes", f"python3 bench/free_scenes.py HOST_DEMO {steps} {reps}")
    for scene in sorted((ROOT / "host" / "scenes").glob("*.toml")):
        text = scene.read_text()
        parsed = tomllib.loads(text)
        if "box" in parsed or "wall" in parsed:
            continue
        dt = parsed["integrator"]["dt"]
        many = steps // 10 if "near_field" in parsed else steps
        best, why = {}, {}
        with tempfile.TemporaryDirectory() as tmp:
            # The repetitions outermost: a change of the machine's load falls on every
            # path alike.
            for r in range(reps):
                for name, keys in PATHS.items():
                    for count in (many // 5, many):
                        if name in why:
                            continue
                        path = pathlib.Path(tmp) / f"{name}-{count}-{scene.name}"
                        path.write_text(variant(text, dt, count, keys))
                        out = pathlib.Path(tmp) / f"out-{name}-{count}-{r}"
                        used, done = cpu_of([binary, "run", str(path), "--out", str(out),
                                             "--threads", "1"])
                        if done.returncode != 0:
                            lines = done.stderr.strip().splitlines()
                            why[name] = lines[-1] if lines else "failed"
                            continue
                        key = (name, count)
                        best[key] = min(best.get(key, used), used)
        for name in PATHS:
            case = f"{scene.stem}, {name}"
            if name in why:
                print(f"{case}: refused: {why[name]}")
                rows.row(TABLE, case, "seconds a step", f"refused: {why[name]}")
                continue
            full, fifth = best[(name, many)], best[(name, many // 5)]
            step = (full - fifth) / (many - many // 5)
            print(f"{case}: {step:.3e} s a step ({full:.3f} s at {many} steps)")
            rows.row(TABLE, case, "seconds a step", f"{step:.3e}")
            rows.row(TABLE, case, f"CPU seconds, {many} steps", f"{full:.3f}")
    rows.finish()


if __name__ == "__main__":
    main(sys.argv)
