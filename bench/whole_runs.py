"""Times whole runs of shipped free-space scenes under each mobility path that can win
them, and under `auto`: the pair sums (`[free_space] method = "dense"`,
`matrix_free = true`), the fast product (`method = "fast"`, weighed once) and `auto`
(the path its cost model picks, and on the fast product the weighing before every
step, `reweigh`). `bench/free_scenes.py` times the first steps; a run whose cloud
grows a tail moves the crossover as it goes, which only a whole run shows.

Each run is `host-demo run SCENE --out DIR --threads 1` as shipped (duration, output),
one after the other; its CPU seconds (user + system of the child), and for `auto` the
steps it took on the pair sums (`summary.json`'s `pair_sum_steps`).

    python3 bench/whole_runs.py [HOST_DEMO [SCENE...]]     # default: cloud

HOST_DEMO defaults to target/release/host-demo (CARGO_TARGET_DIR honoured). With
HYDRORATTLE_BENCH_MACHINE set, rows go to bench/results/whole_runs.csv; the host test
`free_auto::auto_is_within_a_fifth_of_the_best_over_whole_runs` reads them.
"""

import json
import os
import pathlib
import re
import sys
import tempfile
import tomllib

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import record  # noqa: E402
from free_scenes import cpu_of, set_method  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parent.parent
TABLE = ("whole runs of shipped free-space scenes as shipped, CPU seconds of host-demo "
         "run (one thread, one run after the other), by mobility path")
# Each path: `[free_space] method` and keys for [integrator].
PATHS = {
    "matrix-free": ("dense", {"matrix_free": "true"}),
    "fast": ("fast", {}),
    "auto": ("auto", {}),
}


def variant(text, method, keys):
    """The scene with `[free_space] method` and the `[integrator]` keys set."""
    text = set_method(text, "free_space", method)
    extra = "".join(f"{k} = {v}\n" for k, v in keys.items())
    return re.sub(r"(?m)^\[integrator\]\s*$", "[integrator]\n" + extra.rstrip("\n"), text)


def main(argv):
    target = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    binary = argv[1] if len(argv) > 1 else str(target / "release" / "host-demo")
    scenes = argv[2:] or ["cloud"]
    for name in scenes:
        rows = record.Recorder("whole_runs", f"python3 bench/whole_runs.py HOST_DEMO {name}")
        text = (ROOT / "host" / "scenes" / f"{name}.toml").read_text()
        parsed = tomllib.loads(text)
        steps = round(parsed["integrator"]["duration"] / parsed["integrator"]["dt"])
        with tempfile.TemporaryDirectory() as tmp:
            for path, (method, keys) in PATHS.items():
                file = pathlib.Path(tmp) / f"{path}-{name}.toml"
                file.write_text(variant(text, method, keys))
                out = pathlib.Path(tmp) / f"out-{path}"
                used, done = cpu_of([binary, "run", str(file), "--out", str(out),
                                     "--threads", "1"], 24 * 3600)
                if done is None or done.returncode != 0:
                    sys.exit(f"{name}, {path}: {done.stderr if done else 'timed out'}")
                summary = json.loads((out / "summary.json").read_text())
                case = f"{name}, {path}"
                rows.row(TABLE, case, f"CPU seconds, {steps} steps", f"{used:.2f}")
                print(f"{case}: {used:.1f} CPU s", flush=True)
                if path == "auto":
                    on_pairs = summary.get("pair_sum_steps")
                    resolved = tomllib.loads((out / "scene.toml").read_text())
                    took = resolved["free_space"]["method"]
                    rows.row(TABLE, case, "path at the start", took)
                    if on_pairs is not None:
                        rows.row(TABLE, case, "steps on the pair sums", str(on_pairs))
                        print(f"  {on_pairs} of {steps} steps on the pair sums", flush=True)
        rows.finish()


if __name__ == "__main__":
    main(sys.argv)
