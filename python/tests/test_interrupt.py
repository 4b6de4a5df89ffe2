"""Ctrl-C during run_scene stops the run between two steps, as SIGINT stops
`host-demo run`: a checkpoint at the step reached, KeyboardInterrupt, and a run that
resume_run continues to the bytes of a run never stopped."""

import json
import os
import re
import signal
import subprocess
import sys
import textwrap
import time

import hydrorattle as hr

DT = 0.05

SCENE = """
[helix]
tails = 8
head_ratio = 1.5
dhat = 1.2

[integrator]
method = "overdamped2"
dt = {dt}
duration = {duration}

[output]
every = 50
"""

CHILD = textwrap.dedent(
    """
    import json, signal, sys
    import hydrorattle as hr

    # A child started without job control may inherit SIGINT ignored: Python then
    # installs no handler, and Ctrl-C would do nothing (as for any Python code).
    signal.signal(signal.SIGINT, signal.default_int_handler)
    print("started", flush=True)
    try:
        hr.run_scene(sys.argv[1], sys.argv[2])
        print(json.dumps({"finished": True}))
    except KeyboardInterrupt as e:
        print(json.dumps({"checkpoint": str(e.checkpoint), "step": e.step, "time": e.time}))
    """
)


def test_ctrl_c_stops_run_scene_between_steps_and_the_run_resumes(tmp_path):
    # About 10^6 steps: minutes of work, stopped after about a second.
    path = tmp_path / "long.toml"
    path.write_text(SCENE.format(dt=DT, duration=50000.0))
    out = tmp_path / "out"
    child = subprocess.Popen(
        [sys.executable, "-c", CHILD, str(path), str(out)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    assert child.stdout.readline().strip() == "started"
    time.sleep(1.5)
    sent = time.monotonic()
    child.send_signal(signal.SIGINT)
    try:
        stdout, stderr = child.communicate(timeout=10)
    except subprocess.TimeoutExpired:
        child.kill()
        raise AssertionError("run_scene went on more than 10 s after Ctrl-C")
    took = time.monotonic() - sent
    assert child.returncode == 0, stderr
    stop = json.loads(stdout.strip().splitlines()[-1])
    assert "finished" not in stop, "the run finished before the signal"
    assert took < 5.0, f"{took:.1f} s from Ctrl-C to the end"
    assert os.path.exists(stop["checkpoint"])
    assert stop["step"] > 0 and abs(stop["time"] - stop["step"] * DT) < 1e-6 * stop["time"]

    # Resumed to 100 steps past the stop, the files are those of one run to that time.
    until = (stop["step"] + 100) * DT
    summary = hr.resume_run(out, until=until)
    assert summary["steps_done"] == stop["step"] + 100
    ref_path = tmp_path / "short.toml"
    ref_path.write_text(SCENE.format(dt=DT, duration=until))
    hr.run_scene(ref_path, tmp_path / "ref")
    for name in ("trajectory.xyz", "observables.csv"):
        assert (out / name).read_bytes() == (tmp_path / "ref" / name).read_bytes(), name


def test_a_huge_until_is_printed_short(tmp_path):
    path = tmp_path / "short.toml"
    path.write_text(SCENE.format(dt=DT, duration=1.0))
    hr.run_scene(path, tmp_path / "out", checkpoint_every=0.5)
    try:
        hr.resume_run(tmp_path / "out", until=1e300)
    except (RuntimeError, ValueError) as e:
        message = str(e)
    else:
        raise AssertionError("resumed to 1e300")
    # Short: no run of 30 digits (1e300 printed in full has 301).
    assert not re.search(r"\d{30}", message) and len(message) < 400, message
