"""Times the shipped scenes that can run more than one way (host/scenes/*.toml without a
wall) under each explicit mobility path: in free space the stored mobility
(`[free_space] method = "dense"`), its compact copy (`compact_products = true`),
matrix-free (`matrix_free = true`) and the fast product (`method = "fast"`); in a box
`[box] method = "ewald"` and `"pse"`. Each is a short run of `host-demo run` (output as
shipped), the CPU seconds of the child process (user + system), best of REPS, at STEPS
steps and at a fifth of them: the difference over the steps between is the time a
step, without the start (reading, checks, files). A scene with a near field runs a
tenth of the steps (its steps cost a hundred times more), a scene of 1,000 spheres or
more a thousandth (at least 5); where the steps between the two counts take under a CPU
second on the first path that runs, the steps are raised until they do (a step of a few
spheres costs microseconds: the clock's 10 ms ticks would otherwise be a large part of
the difference). A run is stopped after LIMIT wall seconds and its path recorded as over
the limit (slower than the paths that finished); a path the scene refuses is recorded
as refused. Each scene's rows are recorded when it is done.

`auto` is not timed here: it runs the path its cost model resolves to, and the host
test `free_auto::auto_is_within_a_fifth_of_the_best` resolves it (with the model of the
code under test) and checks that path's recorded time against the fastest.

    python3 bench/free_scenes.py [HOST_DEMO [STEPS [REPS [LIMIT [SCENE...]]]]]
    # 5000 steps, best of 3, 60 s a run, every scene

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
    # As `auto` resolves it: the fast product, matrix-free.
    "fast": ("free_space", "fast", {"matrix_free": "true"}),
}
BOX_PATHS = {
    "ewald": ("box", "ewald", {}),
    "pse": ("box", "pse", {}),
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


def cpu_of(cmd, limit):
    """Runs `cmd` for at most `limit` wall seconds; its CPU seconds (user + system) and
    exit status, or None for the status where it ran out of time (then killed)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    try:
        done = subprocess.run(cmd, capture_output=True, text=True, timeout=limit)
    except subprocess.TimeoutExpired:
        done = None
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    used = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return used, done


def main(argv):
    target = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    binary = argv[1] if len(argv) > 1 else str(target / "release" / "host-demo")
    steps = int(argv[2]) if len(argv) > 2 else 5000
    reps = int(argv[3]) if len(argv) > 3 else 3
    limit = float(argv[4]) if len(argv) > 4 else 60.0
    only = argv[5:]
    command = f"python3 bench/free_scenes.py HOST_DEMO {steps} {reps} {limit:g}"
    for scene in sorted((ROOT / "host" / "scenes").glob("*.toml")):
        if only and scene.stem not in only:
            continue
        # Each scene's rows are recorded as it finishes: a stopped run keeps the others.
        rows = record.Recorder("free_scenes", command + "".join(f" {o}" for o in only))
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

        def run(tmp, name, path, count, tag):
            """One run of `count` steps by `path`: its CPU seconds, or None (why[name] set)."""
            file = pathlib.Path(tmp) / f"{name}-{count}-{scene.name}"
            file.write_text(variant(text, dt, count, path))
            out = pathlib.Path(tmp) / f"out-{name}-{count}-{tag}"
            used, done = cpu_of([binary, "run", str(file), "--out", str(out),
                                 "--threads", "1"], limit)
            if done is None:
                why[name] = f"over {limit:g} s for {count} steps"
                return None
            if done.returncode != 0:
                lines = done.stderr.strip().splitlines()
                why[name] = "refused: " + (lines[-1] if lines else "failed")
                return None
            return used

        with tempfile.TemporaryDirectory() as tmp:
            # A probe of the first path that runs: steps raised until the steps between
            # the two counts take at least a CPU second (the clock's ticks are 10 ms).
            for name, path in paths.items():
                short = run(tmp, name, path, many // 5, "probe")
                long = run(tmp, name, path, many, "probe") if short is not None else None
                while long is not None and long - short < 1.0 and many < 10**7:
                    many *= 4 if long - short < 0.25 else 2
                    short = run(tmp, name, path, many // 5, "probe")
                    long = run(tmp, name, path, many, "probe") if short is not None else None
                if long is not None:
                    break
            why.clear()
            # The repetitions outermost: a change of the machine's load falls on every
            # path alike.
            for r in range(reps):
                for name, path in paths.items():
                    for count in (many // 5, many):
                        if name in why:
                            continue
                        used = run(tmp, name, path, count, r)
                        if used is not None:
                            key = (name, count)
                            best[key] = min(best.get(key, used), used)
        per_step = {}
        for name in paths:
            case = f"{scene.stem}, {name}"
            if name in why:
                print(f"{case}: {why[name]}")
                rows.row(TABLE, case, "seconds a step", why[name])
                continue
            full, fifth = best[(name, many)], best[(name, many // 5)]
            step = (full - fifth) / (many - many // 5)
            per_step[name] = step
            print(f"{case}: {step:.3e} s a step ({full:.3f} s at {many} steps)", flush=True)
            rows.row(TABLE, case, "seconds a step", f"{step:.3e}")
            rows.row(TABLE, case, f"CPU seconds, {many} steps", f"{full:.3f}")
        rows.finish()


if __name__ == "__main__":
    main(sys.argv)
