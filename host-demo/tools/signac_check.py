"""Opens a `host-demo sweep` folder with signac and checks that signac sees every point
under the id host-demo gave it: signac lists the jobs of the workspace, recomputes each
id from its state point (Project.check raises on a mismatch), and opens the same job
from the state point alone.

    python host-demo/tools/signac_check.py DIR
"""

import json
import os
import sys

import signac


def main(d):
    project = signac.get_project(d, search=False)
    points = sorted(os.listdir(os.path.join(d, "points")))
    jobs = {job.id: job for job in project}
    assert sorted(jobs) == points, f"signac sees {sorted(jobs)}, the sweep has {points}"
    project.check()
    for i in points:
        with open(os.path.join(d, "points", i, "signac_statepoint.json")) as f:
            sp = json.load(f)
        job = project.open_job(sp)
        assert job.id == i, f"signac gives {sp} the id {job.id}, host-demo {i}"
        assert job.isfile("summary.json"), f"{i}: no summary.json"
    found = list(project.find_jobs({"helix.dhat": 1.05}))
    print(f"signac {signac.__version__}: {len(jobs)} jobs, ids equal to host-demo's; "
          f"{len(found)} with helix.dhat = 1.05")


if __name__ == "__main__":
    main(sys.argv[1])
