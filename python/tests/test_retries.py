"""A thermal step the kernel refuses is retried as shorter steps along a Brownian
bridge, and the Report says so: the count of each call against the count the CLI's
run loop keeps for the same scene (summary.json's "retries")."""

import hydrorattle as hr

# A free-draining 8-bead chain at kT = 1 and dt = 3: kicks of about half a bond, so
# that a few percent of the steps have no projection near the start and are retried.
PARTICLES = "\n".join(
    f"[[particle]]\nposition = [{2.2 * i}, 0.0, 0.0]\nradius = 1.0\ndensity = 1.0\n"
    for i in range(8)
)
BONDS = "\n".join(f"[[bond]]\nbetween = [{i}, {i + 1}]\n" for i in range(7))
SCENE = f"""
[gravity]
acceleration = [0.0, 0.0, 0.0]

{PARTICLES}
{BONDS}
[model]
hydrodynamics = "free-draining"
overlap = "allow"

[integrator]
method = "overdamped"
dt = 3.0
duration = 1500.0
solver = "newton"

[output]
every = 100

[brownian]
temperature = 1.0
seed = 1
"""


def test_the_report_counts_the_retried_steps_as_the_cli_does(tmp_path):
    path = tmp_path / "chain.toml"
    path.write_text(SCENE)
    summary = hr.run_scene(path, tmp_path / "out")
    want = summary["retries"]
    assert want["steps"] > 5, want  # the scene retries: the test means something

    s = hr.System.from_scene_text(SCENE)
    first = s.step(200)
    rest = s.step(300)
    assert first.steps + rest.steps == summary["steps_done"] == 500
    assert first.retried_steps + rest.retried_steps == want["steps"]
    assert first.retry_substeps + rest.retry_substeps == want["substeps"]
    # Each retried step took 2, 4, 8, ... or 128 shorter ones.
    assert 2 * want["steps"] <= want["substeps"] <= 128 * want["steps"]
    assert "retried_steps" in repr(rest)

    # Without noise nothing is retried.
    quiet = hr.System.from_scene_text(SCENE.replace("temperature = 1.0", "temperature = 0.0"))
    assert quiet.step(50).retried_steps == 0
