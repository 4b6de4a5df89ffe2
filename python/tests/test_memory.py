"""Allocations too large for the machine raise MemoryError (or the System's storage
limit's ValueError) naming their sizes; the interpreter never aborts. Each call runs in
a child process, so that an abort (SIGABRT, exit 134) is a failed test, not a dead
pytest."""

import json
import subprocess
import sys
import textwrap


def machine_bytes():
    """This machine's memory and swap (Linux), the budget the package checks against."""
    total = 0
    with open("/proc/meminfo") as f:
        for line in f:
            key, value = line.split(":")
            if key in ("MemTotal", "SwapTotal"):
                total += int(value.split()[0]) * 1024
    return total


def dense_bytes(n, rotation, size):
    """The packed lower triangle (9 values a block) and the dense output of the
    mobility of n spheres, in bytes (closed forms)."""
    blocks = 2 * n if rotation else n
    return (blocks * (blocks + 1) // 2 * 9 + (3 * blocks) ** 2) * size


CHILD = textwrap.dedent(
    """
    import json, sys
    import numpy as np
    import hydrorattle as hr

    def attempt(call):
        try:
            call()
            return ["ok", ""]
        except MemoryError as e:
            return ["MemoryError", str(e)]
        except ValueError as e:
            return ["ValueError", str(e)]

    cases = json.loads(sys.argv[1])
    out = {}
    for name, (kind, n, kw) in cases.items():
        rng = np.random.default_rng(1)
        pos = rng.uniform(0, 4000, (n, 3))
        if kind == "mobility":
            out[name] = attempt(lambda: hr.mobility(pos, 1.0, **kw))
        elif kind == "mobility_dot":
            out[name] = attempt(lambda: hr.mobility_dot(pos, 1.0, np.ones((n, 3)), **kw))
        else:
            out[name] = attempt(lambda: hr.System(pos, 1.0, 1.0, dt=0.1, **kw))
    print(json.dumps(out))
    """
)


def run_child(cases):
    r = subprocess.run(
        [sys.executable, "-c", CHILD, json.dumps(cases)], capture_output=True, text=True, timeout=600
    )
    assert r.returncode == 0, f"exit {r.returncode}: {r.stderr[-2000:]}"
    return json.loads(r.stdout)


def test_a_mobility_too_large_for_the_machine_is_a_memory_error():
    have = machine_bytes()
    cases = {}
    for precision, size in (("f64", 8), ("f32", 4)):
        for rotation in (False, True):
            for box in (None, (1e4, 1e4, 1e4)):
                n = 40000
                while dense_bytes(n, rotation, size) <= have:
                    n *= 2
                name = f"{precision} rotation={rotation} box={box} N={n}"
                kw = dict(precision=precision, rotation=rotation, box=box)
                cases[name] = ("mobility", n, kw)
    # The packed grand mobility of mobility_dot with rotation: tri(2N) blocks of 72 B.
    n = 50000
    while (2 * n) * (2 * n + 1) // 2 * 72 <= have:
        n *= 2
    cases[f"mobility_dot rotation N={n}"] = ("mobility_dot", n, dict(rotation=True))
    for name, (kind, result) in run_child(cases).items():
        assert kind == "MemoryError", f"{name}: {kind} {result}"
        assert "GiB" in result and "spheres" in result, f"{name}: {result}"


def test_a_pse_grid_too_large_for_the_machine_is_a_memory_error():
    # Two spheres in a box of 1000 by PSE at its default tolerance: a grid of about
    # 148 GB ("auto" takes Ewald there).
    if machine_bytes() > 148e9:
        return
    cases = {"pse": ("mobility_dot", 2, dict(box=(1000.0, 1000.0, 1000.0), method="pse"))}
    kind, message = run_child(cases)["pse"]
    assert kind == "MemoryError" and "grid" in message, message


def test_a_system_too_large_is_refused_with_its_size():
    cases = {
        f"{name}": ("System", 40000, kw)
        for name, kw in {
            "rotation": dict(rotation=True),
            "box f32": dict(box=(1e4, 1e4, 1e4), allow_overlap=True, precision="f32"),
        }.items()
    }
    for name, (kind, message) in run_child(cases).items():
        assert kind == "ValueError" and "GiB of step storage" in message, f"{name}: {message}"


def test_a_contact_capacity_past_counting_is_refused_as_such():
    # 2^62 is past the scenes' range; 2^32 is in it, and its storage is past counting
    # (the kernel's layout arithmetic would wrap to a few hundred bytes).
    cases = {"2^62": ("System", 2, dict(contacts=2**62)), "2^32": ("System", 2, dict(contacts=2**32))}
    out = run_child(cases)
    kind, message = out["2^62"]
    assert kind == "ValueError" and "from 1 to 2^32" in message, message
    kind, message = out["2^32"]
    assert kind == "ValueError" and "too many to size" in message, message
