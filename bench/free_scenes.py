"""Times the shipped scenes that can run more than one way (host/scenes/*.toml without a
wall) under each explicit mobility path and under `auto`: in free space the stored
mobility (`[free_space] method = "dense"`), its compact copy (`compact_products =
true`), matrix-free (`matrix_free = true`), the fast product (`method = "fast"`) and
`method = "auto"`; in a box `[box] method = "ewald"`, `"pse"` and `"auto"`. Each is a
short run of `host-demo run` (output as shipped), the CPU seconds of the child process
(user + system), best of REPS, at STEPS steps and at a fifth of them: the difference
over the steps between is the time a step, without the start (reading, checks, files).
A scene with a near field runs a tenth of the steps (its steps cost a hundred times
more), a scene of 1,000 spheres or more a thousandth (at least 5); where the shorter
run of the first path takes under 0.3 CPU seconds, the steps are raised so that it
takes about that (a step of a few spheres costs microseconds: the clock's 10 ms ticks
would otherwise be a large part of the difference). A path the scene
refuses is recorded as refused; for each scene the ratio of `auto` to the fastest
explicit path is recorded. The host test `free_auto::auto_is_within_a_fifth_of_the_best`
checks the path `auto` picks against these rows.

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
# Each path: the table whose `method` it sets, that method, and keys for [integrator].
FREE_PATHS = {
    "dense": ("free_space", "dense", {}),
    "compact": ("free_space", "dense", {"compact_products": "true"}),
    "matrix-free": ("free_space", "dense", {"matrix_free": "true"}),
    "fast": ("free_space", "fast", {}),
    "auto": ("free_space", "auto", {}),
}
BOX_PATHS = {
    "ewald": ("box", "ewald", {}),
    "pse": ("box", "pse", {}),
    "auto": ("box", "auto", {}),
}


def set_method(text, table, method):
    """`text` with `[table] method = "method"` (the table added where it is missing)."""
    head = re.search(rf"(?m)^\[{table}\]\s*$", text)
    if head is None:
        return text.rstrip("\n") + f'\n\n[{table}]\nmethod = "{method}"\n'
    rest = text[head.end():]
    end = re.search(r"(?m)^\[", rest)
    body = rest[: end.start()] if end else rest
    line = f'method = "{method}"'
    if re.search(r"(?m)^method\s*=.*$", body):
        body = re.sub(r"(?m)^method\s*=.*$", line, body, count=1)
    else:
        body = "\n" + line + body
    return text[: head.end()] + body + (rest[end.start():] if end else "")


def variant(text, dt, steps, path):
    """The scene with `duration` set to `steps` steps and `path` applied."""
    table, method, keys = path
    text = re.sub(r"(?m)^duration\s*=.*$", f"duration = {dt * steps!r}", text)
    text = set_method(text, table, method)
    extra = "".join(f"{k} = {v}\n" for k, v in keys.items())
    return re.sub(r"(?m)^\[integrator\]\s*$", "[integrator]\n" + extra.rstrip("\n"), text)


def count_of(parsed):
    """The scene's sphere count (particles, or a generator's count)."""
    for gen in ("cloud", "suspension"):
        if gen in parsed:
            return parsed[gen]["count"]
    if "helix" in parsed:
        return parsed["helix"].get("beads", 25)
    return len(parsed.get("particle", []))


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
        if "wall" in parsed:
            continue
        paths = BOX_PATHS if "box" in parsed else FREE_PATHS
        dt = parsed["integrator"]["dt"]
        many = steps // 10 if "near_field" in parsed else steps
        if count_of(parsed) >= 1000:
            many = max(5, steps // 1000)
        best, why = {}, {}
        with tempfile.TemporaryDirectory() as tmp:
            # A probe of the first path that runs: enough steps for the ticks.
            for path in paths.values():
                file = pathlib.Path(tmp) / f"probe-{scene.name}"
                file.write_text(variant(text, dt, many // 5, path))
                used, done = cpu_of([binary, "run", str(file), "--out",
                                     str(pathlib.Path(tmp) / "out-probe"), "--threads", "1"])
                if done.returncode == 0:
                    if used < 0.3:
                        many = int(many * min(100.0, 0.3 / max(used, 0.01)))
                    break
            # The repetitions outermost: a change of the machine's load falls on every
            # path alike.
            for r in range(reps):
                for name, path in paths.items():
                    for count in (many // 5, many):
                        if name in why:
                            continue
                        file = pathlib.Path(tmp) / f"{name}-{count}-{scene.name}"
                        file.write_text(variant(text, dt, count, path))
                        out = pathlib.Path(tmp) / f"out-{name}-{count}-{r}"
                        used, done = cpu_of([binary, "run", str(file), "--out", str(out),
                                             "--threads", "1"])
                        if done.returncode != 0:
                            lines = done.stderr.strip().splitlines()
                            why[name] = lines[-1] if lines else "failed"
                            continue
                        key = (name, count)
                        best[key] = min(best.get(key, used), used)
        per_step = {}
        for name in paths:
            case = f"{scene.stem}, {name}"
            if name in why:
                print(f"{case}: refused: {why[name]}")
                rows.row(TABLE, case, "seconds a step", f"refused: {why[name]}")
                continue
            full, fifth = best[(name, many)], best[(name, many // 5)]
            step = (full - fifth) / (many - many // 5)
            per_step[name] = step
            print(f"{case}: {step:.3e} s a step ({full:.3f} s at {many} steps)")
            rows.row(TABLE, case, "seconds a step", f"{step:.3e}")
            rows.row(TABLE, case, f"CPU seconds, {many} steps", f"{full:.3f}")
        explicit = {k: v for k, v in per_step.items() if k != "auto"}
        if "auto" in per_step and len(explicit) > 1:
            best_name = min(explicit, key=explicit.get)
            ratio = per_step["auto"] / explicit[best_name]
            print(f"{scene.stem}: auto / best ({best_name}) = {ratio:.2f}")
            rows.row(TABLE, f"{scene.stem}, auto", f"auto / best explicit ({best_name})",
                     f"{ratio:.2f}")
    rows.finish()


if __name__ == "__main__":
    main(sys.argv)
