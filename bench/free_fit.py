"""Fits the free-space cost model's constants (host/src/scene/free_cost.rs) to the rows
of every shape that `examples/free_cost.rs` recorded at one commit, together: one fit per
path over every shape and count, so that a fixed cost is told from a cost per pair by
shapes whose pair counts differ (a chain against clouds of three volume fractions).

Forms, minimising relative residuals with non-negative constants (as the example's
`shared/fit.rs`, dropping the most negative constant and refitting):

* dense assembly and product, compact copy and product, matrix-free product and spin
  pass: `c0 + c1 tri(N)` (`tri(N) = N (N + 1) / 2` packed blocks);
* grand assembly: `c0 + c1 tri(2N)`; Cholesky: `c0 + c1 N^3`;
* fast product (both tolerances, both parameter rules) and grand product (both
  tolerances): `c0 + cG M log2 M + cN (N + 2 pairs) + cS N P^3`, with the padded grid's
  points `M`, the window's `P^3` and the near pairs each row recorded.

    python3 bench/free_fit.py COMMIT            # prints the constants
    HYDRORATTLE_BENCH_MACHINE=<id> python3 bench/free_fit.py COMMIT   # and records them
    python3 bench/free_fit.py --brownian COMMIT...   # the Lanczos iterations' constants

`--brownian` fits `host/src/scene/free_noise.rs`: the Lanczos iterations that
`examples/free_brownian.rs` recorded (at the commits given, every shape and count),
with the inverse root (the matrix-free path's midpoint; the stored path's is the same
run) and without (the fast path), each against `c0 + c1 sqrt(S) + c2 sqrt(f)`,
`S = 1 + 6 N a / (5 R)` with `R` half the longest edge of the bounding box plus a
radius, `f = N a^3 / V` with `V` the box widened by a radius each side (a cloud's
edges `2 (N / phi)^(1/3)`; the helical chain's from its recurrence), as the model
computes them.

With HYDRORATTLE_BENCH_MACHINE set the constants go to bench/results/free_cost.csv as
rows of "free-space cost model constants", which the host test
`the_constants_are_the_recorded_fit` checks the code's against.
"""

import csv
import math
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import record  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parent.parent
TABLE = "free-space product paths, unit spheres, f64, one thread, CPU seconds a call"
# The pair paths timed against `tri(N)`: the name each is recorded as, its constants' prefix.
PAIRS = {
    "dense assembly": "DENSE_ASSEMBLY",
    "dense product": "DENSE_PRODUCT",
    "compact copy": "COMPACT_COPY",
    "compact product": "COMPACT_PRODUCT",
    "matrix-free product": "FREE",
    "spin pass": "SPIN",
}
FAST_TAGS = ["fast 1e-4", "fast 1e-6", "fast grand-parameter 1e-4", "fast grand-parameter 1e-6"]


def fit(x, t):
    """Non-negative least squares on relative residuals (the example's `fit`)."""
    k = len(x[0])
    on = [True] * k
    while True:
        cols = [c for c in range(k) if on[c]]
        m = len(cols)
        a = [[0.0] * (m + 1) for _ in range(m)]
        for row, ti in zip(x, t):
            w = [row[c] / ti for c in cols]
            for i in range(m):
                for j in range(m):
                    a[i][j] += w[i] * w[j]
                a[i][m] += w[i]
        for i in range(m):
            p = max(range(i, m), key=lambda r: abs(a[r][i]))
            a[i], a[p] = a[p], a[i]
            for r in range(m):
                if r != i:
                    f = a[r][i] / a[i][i]
                    a[r] = [xr - f * xp for xr, xp in zip(a[r], a[i])]
        out = [0.0] * k
        for i, c in enumerate(cols):
            out[c] = a[i][m] / a[i][i]
        worst = min((c for c in range(k) if on[c]), key=lambda c: out[c])
        if out[worst] >= 0.0:
            return out
        on[worst] = False


def misfit(x, t, c):
    """The worst relative misfit, a factor (1 for a perfect fit)."""
    return math.exp(max(abs(math.log(sum(a * b for a, b in zip(r, c)) / ti))
                        for r, ti in zip(x, t)))


def rows_of(commit):
    """{case: {quantity: value}} of the product-path rows measured at `commit`."""
    cases = {}
    with open(ROOT / "bench" / "results" / "free_cost.csv", newline="") as f:
        for r in csv.DictReader(f):
            if r["commit"] == commit and r["measurement"].startswith(TABLE):
                cases.setdefault(r["case"], {})[r["quantity"]] = r["value"]
    return cases


def number(cell, key):
    try:
        return float(cell[key])
    except (KeyError, ValueError):
        return None


def main(argv):
    commit = argv[1]
    cases = rows_of(commit)
    if not cases:
        sys.exit(f"no rows of {TABLE!r} at commit {commit}")
    data = {}

    def add(name, terms, t):
        if t is not None:
            data.setdefault(name, ([], []))[0].append(terms)
            data[name][1].append(t)

    for cell in cases.values():
        b = number(cell, "packed blocks tri(N)")
        n = (math.sqrt(8 * b + 1) - 1) / 2
        for path, name in PAIRS.items():
            add(name, [1.0, b], number(cell, path))
        add("GRAND_ASSEMBLY", [1.0, 2 * n * (2 * n + 1) / 2], number(cell, "grand assembly"))
        add("CHOLESKY", [1.0, n ** 3], number(cell, "dense Cholesky"))
        for tag in FAST_TAGS:
            m = number(cell, f"{tag}: padded grid points M")
            if m is None:
                continue
            p3 = number(cell, f"{tag}: window points P^3")
            pairs = number(cell, f"{tag}: near pairs")
            terms = [1.0, m * math.log2(m), n + 2 * pairs, n * p3]
            add("FAST", terms, number(cell, tag.replace("fast ", "fast product ", 1)))
            if "grand" in tag:
                add("GRAND", terms, number(cell, tag.replace("grand-parameter", "grand product")))
    suffixes = {2: ["FIXED", "BLOCK"], 4: ["FIXED", "GRID", "NEAR", "SPREAD"]}
    suffixes_of = {"CHOLESKY": ["FIXED", "CUBE"]}
    rows = record.Recorder("free_cost", f"python3 bench/free_fit.py {commit}", exact=True)
    table = (f"free-space cost model constants (seconds a call per term), fitted to the "
             f"rows of every shape at {commit}")
    for name, (x, t) in data.items():
        c = fit(x, t)
        names = suffixes_of.get(name, suffixes[len(c)])
        for s, v in zip(names, c):
            print(f"pub const {name}_{s}: f64 = {v:.4e};")
            rows.row(table, name.lower(), f"{name}_{s}", f"{v:.4e}")
        worst = misfit(x, t, c)
        print(f"// {name}: {len(t)} rows, worst misfit {worst:.2f}")
        rows.row(table, name.lower(), "worst misfit (factor)", f"{worst:.2f}")
    rows.finish()


BROWNIAN = "free-space Brownian steps, unit spheres, f64, one thread, CPU seconds a step"


def helix_extent(n):
    """The bounding box's edges of the helical chain of `examples/shared/free_shapes.rs`."""
    at, lo, hi = [0.0] * 3, [0.0] * 3, [0.0] * 3
    for k in range(1, n):
        t = 0.6 * k
        d = [math.cos(t), math.sin(t), 0.8]
        norm = math.sqrt(sum(x * x for x in d))
        for c in range(3):
            at[c] += 3.0 * d[c] / norm
            lo[c], hi[c] = min(lo[c], at[c]), max(hi[c], at[c])
    return [h - l for h, l in zip(hi, lo)]


def iteration_terms(case):
    """`[1, sqrt(S), sqrt(f)]` of a case named "SHAPE, N = n" (unit spheres)."""
    shape, n = case.split(", N = ")
    n = int(n)
    if shape.startswith("cloud "):
        extent = [2.0 * (n / float(shape.split()[1])) ** (1 / 3)] * 3
    else:
        extent = helix_extent(n)
    r = 0.5 * max(extent) + 1.0
    volume = math.prod(e + 2.0 for e in extent)
    return [1.0, math.sqrt(1.0 + 1.2 * n / r), math.sqrt(n / volume)]


def brownian(commits):
    """Fits and records the Lanczos iterations' constants."""
    data = {"MIDPOINT": ([], []), "ROOT": ([], [])}
    paths = {"matrix-free": "MIDPOINT", "fast 1e-4": "ROOT"}
    with open(ROOT / "bench" / "results" / "free_cost.csv", newline="") as f:
        for r in csv.DictReader(f):
            if r["commit"] not in commits or not r["measurement"].startswith(BROWNIAN):
                continue
            for path, name in paths.items():
                if r["quantity"] == f"{path} Brownian step: Lanczos iterations":
                    m = float(r["value"])
                    if m > 0:  # 0: the Cholesky factor
                        data[name][0].append(iteration_terms(r["case"]))
                        data[name][1].append(m)
    rows = record.Recorder("free_cost", f"python3 bench/free_fit.py --brownian {' '.join(commits)}",
                           exact=True)
    table = (f"free-space Lanczos iterations model constants (iterations per term), fitted "
             f"to the Brownian steps at {' '.join(commits)}")
    for name, (x, t) in data.items():
        if not t:
            sys.exit(f"no Lanczos iterations of {name} at {commits}")
        c = fit(x, t)
        for s, v in zip(["FIXED", "SPREAD", "FILL"], c):
            print(f"pub const {name}_{s}: f64 = {v:.4e};")
            rows.row(table, name.lower(), f"{name}_{s}", f"{v:.4e}")
        worst = misfit(x, t, c)
        print(f"pub const {name}_MISFIT: f64 = {worst:.2f};  // {len(t)} rows")
        rows.row(table, name.lower(), f"{name}_MISFIT", f"{worst:.2f}")
    rows.finish()


if __name__ == "__main__":
    if sys.argv[1:2] == ["--brownian"]:
        brownian(sys.argv[2:])
    else:
        main(sys.argv)
