"""System: physics from Python, transactional failures, threads, signals, memory."""

import _thread
import math
import signal
import threading
import time

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, event, given, settings
from hypothesis import strategies as st

import hydrorattle as hr

RHO = 4.5  # a lone unit sphere settles at speed 1 under |g| = 1, eta = 1


def dimer_rate(a1, a2, d, drho_g=RHO, eta=1.0):
    """Turning rate C of a settling rigid dimer (far-field RPY), derived in
    tests/kernel/dynamics.rs: d theta / dt = -C sin theta, so
    tan(theta / 2) = tan(theta0 / 2) exp(-C t)."""
    weight = lambda a: 4.0 / 3.0 * math.pi * a**3 * drho_g  # noqa: E731
    mu = lambda a: 1.0 / (6.0 * math.pi * eta * a)  # noqa: E731
    big_a = (1.0 + (a1 * a1 + a2 * a2) / (3.0 * d * d)) / (8.0 * math.pi * eta * d)
    return (weight(a2) * (mu(a2) - big_a) - weight(a1) * (mu(a1) - big_a)) / d


def dimer_theta(dt, t_end=4.0, theta0=2.5, phi=0.7, method="overdamped2"):
    a1, a2, d = 1.0, 2.0, 4.5
    e0 = np.array([math.sin(theta0) * math.cos(phi), math.sin(theta0) * math.sin(phi), -math.cos(theta0)])
    p0 = np.array([0.5, -0.25, 1.0])
    s = hr.System([p0, p0 + d * e0], [a1, a2], RHO, bonds=[[0, 1]], dt=dt, method=method)
    s.step(round(t_end / dt))
    e = s.positions[1] - s.positions[0]
    assert np.linalg.norm(e) == pytest.approx(d, rel=1e-9)
    return math.atan2(math.hypot(e[0], e[1]), -e[2])


def test_settling_dimer_turns_as_the_closed_form():
    c = dimer_rate(1.0, 2.0, 4.5)
    exact = 2.0 * math.atan(math.tan(2.5 / 2) * math.exp(-c * 4.0))
    errors = [abs(dimer_theta(dt) - exact) for dt in (0.04, 0.02)]
    assert errors[1] < 1e-4
    # Heun: second order, measured from the two step sizes.
    order = math.log2(errors[0] / errors[1])
    assert 1.7 < order < 2.3, order
    first = abs(dimer_theta(0.01, method="overdamped") - exact)
    assert first < 5e-3


def chain(n, radius=1.0, gap=1.5):
    pos = np.zeros((n, 3))
    pos[:, 0] = np.arange(n) * 2 * radius * gap
    pos[:, 2] = 0.3 * np.sin(np.arange(n))
    return pos, [[i, i + 1] for i in range(n - 1)]


def test_a_step_whose_force_raises_changes_nothing():
    pos, bonds = chain(5)
    s = hr.System(pos, 1.0, RHO, bonds=bonds, dt=0.05, method="overdamped2")
    s.step(3)
    before = s.state_bits()
    calls = []

    def force(p):
        calls.append(1)
        if len(calls) == 2:  # the corrector's evaluation of the first step
            raise RuntimeError("boom")
        return np.zeros_like(p)

    with pytest.raises(RuntimeError, match="boom"):
        s.step(5, force=force)
    assert s.state_bits() == before


def test_a_failed_step_changes_nothing_and_names_its_stage():
    pos, bonds = chain(8)
    s = hr.System(pos, 1.0, RHO, bonds=bonds, dt=0.05, solver="sweep", max_iterations=1, tolerance=1e-14)
    before = s.state_bits()
    with pytest.raises(hr.ConvergenceError) as e:
        s.step(10)
    assert isinstance(e.value, hr.StepError)
    assert e.value.kind == "no_convergence" and e.value.stage == "positions"
    assert e.value.index == 1 and e.value.value > 1e-14
    assert s.state_bits() == before
    with pytest.raises(hr.NonFiniteError) as e:
        s.step(1, force=lambda p: np.where(np.arange(len(p))[:, None] == 3, np.inf, 0.0) + 0 * p)
    assert e.value.index == 3
    assert s.state_bits() == before


def test_a_failed_thermal_step_leaves_the_noise_generator_as_it_was():
    pos, bonds = chain(4)
    kw = dict(bonds=bonds, dt=0.01, temperature=0.5, seed=7)
    a = hr.System(pos, 1.0, RHO, **kw)
    b = hr.System(pos, 1.0, RHO, **kw)
    a.step(3)
    b.step(3)
    with pytest.raises(hr.NonFiniteError):
        a.step(1, force=lambda p: np.full_like(p, np.nan))
    a.step(20)
    b.step(20)
    assert a.state_bits() == b.state_bits()
    c = hr.System(pos, 1.0, RHO, **{**kw, "seed": 8})
    c.step(23)
    assert c.state_bits() != a.state_bits()


METHODS = ["overdamped", "overdamped2", "rattle", "rattle-stable"]


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    n=st.integers(2, 7),
    seed=st.integers(0, 2**31),
    method=st.sampled_from(METHODS),
    solver=st.sampled_from(["auto", "sweep", "newton", "krylov"]),
    hydro=st.sampled_from(["rpy", "oseen", "free-draining"]),
    dt=st.floats(1e-3, 2.0),
    steps=st.integers(1, 6),
    precision=st.sampled_from(["f64", "f32"]),
    temperature=st.sampled_from([None, 0.0, 0.2]),
)
def test_a_step_keeps_every_bond_or_raises_and_changes_nothing(
    n, seed, method, solver, hydro, dt, steps, precision, temperature
):
    rng = np.random.default_rng(seed)
    radii = rng.uniform(0.5, 1.5, n)
    pos = np.zeros((n, 3))
    for i in range(1, n):
        d = rng.normal(size=3)
        pos[i] = pos[i - 1] + d / np.linalg.norm(d) * (radii[i] + radii[i - 1]) * rng.uniform(1.05, 2.0)
    bonds = [[i, i + 1] for i in range(n - 1)]
    try:
        s = hr.System(pos, radii, rng.uniform(0.5, 5.0, n), bonds=bonds, dt=dt, method=method,
                      solver=solver, hydro=hydro, allow_overlap=True, precision=precision,
                      temperature=temperature, seed=seed)
    except ValueError as e:
        # The random walk put one sphere inside another, or the kernel refuses the
        # combination (thermal noise with overdamped2, say) when the system is built.
        assert "inside" in str(e) or getattr(e, "kind", None) == "unsupported", e
        assume(False)
    lengths = s.lengths
    tol = 1e-8 if precision == "f64" else 1e-3
    event(method)
    for _ in range(steps):
        before = s.state_bits()
        try:
            s.step(1)
        except hr.StepError as e:
            assert s.state_bits() == before
            event(f"raised {e.kind}")
            return
        p = s.positions
        r = np.linalg.norm(p[1:] - p[:-1], axis=1)
        assert np.max(np.abs(r - lengths) / lengths) <= tol


def test_step_releases_the_gil():
    pos, bonds = chain(25)
    s = hr.System(pos, 1.0, RHO, bonds=bonds, dt=0.01)
    ticks = []
    done = threading.Event()

    def count():
        while not done.is_set():
            ticks.append(1)
            time.sleep(0)

    t = threading.Thread(target=count)
    t.start()
    time.sleep(0.05)
    start = len(ticks)
    s.step(3000)
    during = len(ticks) - start
    done.set()
    t.join()
    assert during > 100, during


def test_ctrl_c_stops_between_steps_in_a_consistent_state():
    pos, bonds = chain(25)
    # However many steps 0.3 s holds (the chain folds as it settles, and a fast machine
    # gets there): overlapping spheres take RPY's overlapping branch, not a refusal.
    s = hr.System(pos, 1.0, RHO, bonds=bonds, dt=0.001, allow_overlap=True)
    lengths = s.lengths
    # Ctrl-C every 0.3 s until the steps stop.
    stopped = threading.Event()

    def ctrl_c():
        while not stopped.wait(0.3):
            _thread.interrupt_main()

    timer = threading.Thread(target=ctrl_c)
    # A shell's background job starts with SIGINT ignored, and Python then leaves it
    # ignored: interrupt_main() would do nothing. Ctrl-C's own handler, for this test.
    old = signal.signal(signal.SIGINT, signal.default_int_handler)
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            s.step(10**9)
    finally:
        stopped.set()
        timer.join()
        signal.signal(signal.SIGINT, old)
        try:  # an interrupt sent just as the steps stopped is raised here, not later
            time.sleep(0.01)
        except KeyboardInterrupt:
            pass
    steps = s.time / s.dt
    assert steps > 0 and abs(steps - round(steps)) < 1e-6 * steps
    p = s.positions
    assert np.max(np.abs(np.linalg.norm(p[1:] - p[:-1], axis=1) - lengths)) < 1e-9
    s.step(1)


def rss_kib():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * 4


@pytest.mark.skipif(not __import__("os").path.exists("/proc/self/statm"), reason="needs /proc")
def test_many_single_steps_hold_memory_flat():
    pos, bonds = chain(4)
    s = hr.System(pos, 1.0, RHO, bonds=bonds, dt=1e-4)
    for _ in range(10_000):
        s.step(1)
    before = rss_kib()
    for _ in range(100_000):
        s.step(1)
    grown = rss_kib() - before
    assert grown < 1024, f"RSS grew by {grown} KiB over 1e5 calls"


def test_run_yields_frames_up_to_the_end():
    s = hr.System.helix(tails=6, integrator={"dt": 0.01, "method": "rattle-stable"})
    frames = list(s.run(until=0.25, every=10))
    assert [round(f.time / 0.01) for f in frames] == [0, 10, 20, 25]
    assert frames[0].report is None and frames[-1].report.steps == 5
    assert frames[-1].positions.shape == (7, 3)
    assert np.array_equal(frames[-1].positions, s.positions)


def test_bad_system_input_is_refused():
    pos, bonds = chain(3)
    with pytest.raises(ValueError, match="particle 1: radius"):
        hr.System(pos, [1, 0, 1], RHO, bonds=bonds, dt=0.1)
    with pytest.raises(ValueError, match="bond 1: particle index 7"):
        hr.System(pos, 1.0, RHO, bonds=[[0, 1], [1, 7]], dt=0.1)
    with pytest.raises(TypeError, match='unexpected parameter "viscosty"'):
        hr.System(pos, 1.0, RHO, bonds=bonds, dt=0.1, viscosty=2.0)
    with pytest.raises(TypeError, match="dt"):
        hr.System(pos, 1.0, RHO, bonds=bonds)
    with pytest.raises(ValueError, match="method must be one of"):
        hr.System(pos, 1.0, RHO, bonds=bonds, dt=0.1, method="verlet")
    # Parameters the first step would refuse are refused when the system is built.
    with pytest.raises(ValueError, match="time step") as e:
        hr.System(pos, 1.0, RHO, bonds=bonds, dt=-0.1)
    assert e.value.kind == "bad_time_step"


def test_helix_keys_build_the_scene_files_chain():
    import pathlib

    scene = pathlib.Path(__file__).resolve().parents[2] / "host" / "scenes" / "figure1c.toml"
    a = hr.System.from_scene(scene)
    b = hr.System.helix(
        tails=24, head_ratio=2.0, dhat=1.05, radius=2.0, pitch=7.0, density=4.5,
        contact={"model": "hard"},
        integrator={"method": "overdamped2", "dt": 0.1, "solver": "newton", "tolerance": 1e-10,
                    "max_iterations": 500},
    )
    assert a.state_bits() == b.state_bits()
    a.step(20)
    b.step(20)
    assert a.state_bits() == b.state_bits()
    assert len(b) == 25 and b.radii[0] == 2.0


def test_state_can_be_set_and_copied():
    pos, bonds = chain(4)
    s = hr.System(pos, 1.0, RHO, bonds=bonds, dt=0.02, temperature=0.3, seed=5)
    s.step(5)
    twin = s.copy()
    s.step(10)
    assert twin.time == pytest.approx(0.1) and s.state_bits() != twin.state_bits()
    twin.step(10)
    assert s.state_bits() == twin.state_bits()
    moved = s.positions + [1.0, -2.0, 0.5]  # a rigid shift keeps every bond
    s.positions = moved
    assert np.array_equal(s.positions, moved)
    s.set_state(velocities=np.ones((4, 3)), time=7.0)
    assert s.time == 7.0 and np.all(s.velocities == 1)
    s.step(1)
    bad = s.positions.copy()
    bad[2] += 0.3
    with pytest.raises(ValueError, match="particle 1: non-finite positions"):
        s.positions = np.where(np.arange(4)[:, None] == 1, np.nan, bad)
    s.positions = bad
    s.step()  # the constraint solve targets the lengths: the bonds are pulled back
    p = s.positions
    assert np.max(np.abs(np.linalg.norm(p[1:] - p[:-1], axis=1) - s.lengths)) < 1e-9


# The multipliers are as accurate as the solve: a length error `tol d` is a force error
# of about `tol d / (dt mu)`: f32's tolerance (1e-5) leaves about 1e-3 of the tension at
# dt = 0.1 and 1e-2 at dt = 0.01 (measured: 2.4e-3 and 9e-3).
@pytest.mark.parametrize("precision,rel", [("f64", 1e-7), ("f32", 2e-2)])
@pytest.mark.parametrize("method", ["overdamped", "rattle-stable", "springs"])
@pytest.mark.parametrize("hydro", ["rpy", "free-draining"])
def test_vertical_dimer_tension_is_half_the_weight_difference(precision, rel, method, hydro):
    """Two equal spheres, one above the other, settle together: for any pair mobility
    (mu_s - mu_p)(F0 + f0 - F1 - f1) = 0 along the bond, so the bond carries half the
    difference of the buoyant weights, (W0 - W1) / 2, pulling when the lower is
    heavier. Rigid bonds hold it from the first step; springs and the inertial method
    reach it as their transient decays."""
    rho = [6.0, 2.0]  # the lower sphere is the heavier
    weight = [4.0 / 3.0 * math.pi * r for r in rho]
    want = (weight[0] - weight[1]) / 2.0
    one = method == "overdamped"
    s = hr.System(
        [[0.0, 0.0, 0.0], [0.0, 0.0, 3.0]], 1.0, rho, bonds=[[0, 1]],
        dt=0.1 if one else 0.01, method=method, hydro=hydro, precision=precision,
        spring_stiffness=1e3,
    )
    if method != "springs":  # a spring's tension is its law at the current length
        assert s.tensions is None
    s.step(1 if one else 3000)
    got = s.tensions
    assert got.shape == (1,)
    assert got[0] == pytest.approx(want, rel=rel)
    # Upside down, the bond pushes: the same magnitude, the other sign.
    s = hr.System(
        [[0.0, 0.0, 3.0], [0.0, 0.0, 0.0]], 1.0, rho, bonds=[[0, 1]], dt=0.1,
        method="overdamped", hydro=hydro, precision=precision,
    )
    s.step(1)
    assert s.tensions[0] == pytest.approx(-want, rel=rel)


def test_overdamped2_has_no_tensions():
    s = hr.System([[0.0, 0.0, 0.0], [0.0, 0.0, 3.0]], 1.0, [6.0, 2.0], bonds=[[0, 1]],
                  dt=0.01, method="overdamped2")
    s.step(1)
    assert s.tensions is None


def test_lanczos_noise_is_reported_and_keeps_the_bonds():
    """The Krylov square root is chosen by name, reports its iterations (the kernel's
    tests/kernel/lanczos.rs checks its covariance), and the step still holds every bond."""
    pos, bonds = chain(8)
    kw = dict(bonds=bonds, dt=0.01, method="overdamped", temperature=1.0, seed=3)
    lan = hr.System(pos, 1.0, RHO, noise_sqrt="lanczos", **kw)
    chol = hr.System(pos, 1.0, RHO, noise_sqrt="cholesky", **kw)
    r = lan.step(5)
    assert 1 <= r.noise_iterations <= 64
    assert chol.step(5).noise_iterations == 0
    p = lan.positions
    lengths = [np.linalg.norm(p[i] - p[j]) for i, j in bonds]
    assert np.allclose(lengths, lan.lengths, rtol=1e-8)
    with pytest.raises(ValueError):
        hr.System(pos, 1.0, RHO, noise_sqrt="qr", **kw)


def test_rattle_stable_at_temperature_equipartition_of_the_scheme():
    """A lone unit sphere of mass 1 with zeta = 6 pi eta a = 1 under RattleStable at
    kT = 1 and dt = m / zeta (h = 1): the kernel's discretised Langevin step samples
    velocities of variance kT / (m + zeta dt / 2) = 2/3 per component exactly (the
    kernel's tests/kernel/inertial_thermal.rs derives it and checks the dt -> 0 limit kT / m).
    20000 steps, blocks of 400 (the velocity decorrelates in a few steps)."""
    rho = 3.0 / (4.0 * math.pi)
    s = hr.System([[0.0, 0.0, 0.0]], 1.0, rho, dt=1.0, method="rattle-stable",
                  viscosity=1.0 / (6.0 * math.pi), gravity=[0.0, 0.0, 0.0],
                  temperature=1.0, seed=4)
    v2 = np.empty(20000)
    for k in range(v2.size):
        s.step(1)
        v2[k] = np.mean(s.velocities[0] ** 2)
    blocks = v2.reshape(50, -1).mean(axis=1)
    mean, se = blocks.mean(), blocks.std(ddof=1) / math.sqrt(blocks.size)
    assert se < 0.01
    assert abs(mean - 2.0 / 3.0) < 3.0 * se, (mean, se)


def test_a_chain_lands_on_a_wall_from_the_scene_code():
    """The [wall] table through the CLI's scene code (System.helix), and the wall=
    keyword: spheres stop at contact, never below; a sphere below the wall is refused
    with its index."""
    h = -6.0
    s = hr.System.helix(
        tails=4, wall={"height": h}, contact={"model": "hard"},
        integrator={"method": "overdamped", "dt": 0.2},
    )
    for _ in range(60):
        r = s.step(1)
        assert np.all(s.positions[:, 2] - s.radii - h >= -1e-9)
    gap = s.positions[:, 2] - s.radii - h
    assert r.wall_contacts == np.sum(gap < 1e-9) >= 3
    with pytest.raises(hr.SceneError, match="particle 0 is below the wall") as e:
        hr.System.helix(tails=4, wall={"height": 0.0}, integrator={"method": "overdamped", "dt": 0.2})
    assert e.value.line is not None
    one = hr.System([[0.0, 0.0, 2.5]], 1.0, RHO, dt=1.0, wall=0.0)
    one.step(10)
    assert one.positions[0, 2] == pytest.approx(1.0, abs=1e-9)
    with pytest.raises(ValueError, match="particle 1") as e:
        hr.System([[0.0, 0.0, 2.5], [3.0, 0.0, 0.5]], 1.0, RHO, dt=1.0, wall=0.0)
    assert e.value.index == 1


def dimer_closed_form(d, rho, a_top=1.0, a_bottom=2.0):
    """Tension and speed of a rigid dimer settling vertically, the big sphere below (RPY
    far field, eta = 1, g = 1): both spheres move with one velocity U, so with the pair
    block along the bond M and Stokes' mu_k, mu_1 (W_1 + T) + M (W_2 - T) =
    M (W_1 + T) + mu_2 (W_2 - T)."""
    w = [4.0 / 3.0 * math.pi * a**3 * rho for a in (a_top, a_bottom)]
    mu = [1.0 / (6.0 * math.pi * a) for a in (a_top, a_bottom)]
    s = (a_top**2 + a_bottom**2) / d**2
    m = ((1 + s / 3) + (1 - s)) / (8 * math.pi * d)
    t = ((mu[1] - m) * w[1] - (mu[0] - m) * w[0]) / (mu[0] + mu[1] - 2 * m)
    return t, mu[0] * (w[0] + t) + m * (w[1] - t)


@pytest.mark.parametrize("precision", ["f64", "f32"])
@pytest.mark.parametrize("method", ["overdamped", "rattle", "rattle-stable", "springs"])
@pytest.mark.parametrize("dt", [0.01, 0.001])
def test_settling_dimer_tension_in_both_precisions(precision, method, dt):
    """Radii 1 (above) and 2 (below), 4 apart, density 4.5: every method's tension
    against the closed form (14.7596, the issue's figure) in f32 and f64 (f32 rattle read
    16.6, and -0 at dt = 0.001, before the inertial tensions were solved from the
    displacements). Springs: the spring law against the closed form at the stretched
    length, once the stretch has relaxed."""
    d, rho = 4.0, 4.5
    want, u = dimer_closed_form(d, rho)
    assert want == pytest.approx(14.7596, abs=1e-4)
    s = hr.System(
        [[0.3, -0.2, d], [0.3, -0.2, 0.0]], [1.0, 2.0], rho, bonds=[[0, 1]], dt=dt,
        method=method, solver="newton", precision=precision,
    )
    s.set_state(velocities=[[0, 0, -u], [0, 0, -u]])
    s.step(300)
    got = s.tensions[0]
    if method == "springs":
        p = s.positions
        want = dimer_closed_form(np.linalg.norm(p[0] - p[1]), rho)[0]
    tol = {"f64": 1e-5, "f32": 1e-2}[precision]
    assert got == pytest.approx(want, rel=tol), (got, want)


def test_compact_products_keep_the_bonds_and_stay_near_the_f64_run():
    """The f32 copy of the mobility for the Krylov products (700 beads and more):
    every bond still meets the tolerance, and the positions stay within the f32
    copy's rounding of the all-f64 run's."""
    pos, bonds = chain(720)
    kw = dict(bonds=bonds, dt=0.05, solver="krylov", tolerance=1e-10)
    plain = hr.System(pos, 1.0, RHO, **kw)
    compact = hr.System(pos, 1.0, RHO, compact_products=True, **kw)
    plain.step(2)
    compact.step(2)
    p, c = plain.positions, compact.positions
    rest = np.linalg.norm(pos[1:] - pos[:-1], axis=1)
    lengths = np.linalg.norm(c[1:] - c[:-1], axis=1)
    assert np.max(np.abs(lengths - rest)) < 1e-8
    moved = np.max(np.abs(p - pos))
    gap = np.max(np.abs(p - c))
    # Different storage, so not the same bits; f32's rounding of the matrix, 6e-8
    # relative, bounds how far the constrained velocities may differ.
    assert 0 < gap < 1e-5 * moved, (gap, moved)


def test_a_fixed_sphere_holds_still_and_slows_its_neighbour():
    """A pinned sphere (``fixed = true``, the kernel's pin rows) does not move, and a
    free sphere beside it settles at ``(M11 - M12 M22^-1 M21) F``, the two-sphere RPY
    tensors written here from the closed form (docs/CONTACTS.md, pinned spheres)."""
    r1, r2 = np.array([0.2, 0.1, 0.3]), np.array([3.1, 0.8, -0.6])
    a1, a2, g = 1.0, 1.5, np.array([0.3, -0.5, -1.0])
    text = f"""
[fluid]
density = 1.0

[gravity]
acceleration = {g.tolist()}

[[particle]]
position = {r1.tolist()}
radius = {a1}
density = {RHO}

[[particle]]
position = {r2.tolist()}
radius = {a2}
density = 1.0
fixed = true

[integrator]
method = "overdamped"
dt = 0.1
duration = 0.1
"""
    s = hr.System.from_scene_text(text, "fixed.toml")
    before = s.positions
    s.step()
    after = s.positions
    assert np.array_equal(after[1], before[1])
    r = r1 - r2
    d = np.linalg.norm(r)
    q = (a1 * a1 + a2 * a2) / (d * d)
    m12 = ((1 + q / 3) * np.eye(3) + (1 - q) * np.outer(r, r) / (d * d)) / (8 * math.pi * d)
    m11, m22 = np.eye(3) / (6 * math.pi * a1), np.eye(3) / (6 * math.pi * a2)
    force = 4.0 / 3.0 * math.pi * a1**3 * (RHO - 1.0) * g
    want = (m11 - m12 @ np.linalg.solve(m22, m12.T)) @ force
    got = (after[0] - before[0]) / 0.1
    assert np.allclose(got, want, rtol=1e-10, atol=0.0)
