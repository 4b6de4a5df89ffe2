"""Figure 1 (c) of the paper from Python: a head of radius 2 and 24 tails of radius 1
(D = 1.05) settling from a helix, side views at t = 0 and t = 400.

    pip install ./python matplotlib && python python/examples/figure1c.py
"""

import matplotlib.pyplot as plt

import hydrorattle as hr

chain = hr.System.helix(
    tails=24, head_ratio=2.0, dhat=1.05, radius=2.0, pitch=7.0, density=4.5,
    contact={"model": "hard"},
    integrator={"method": "overdamped2", "dt": 0.1, "solver": "newton"},
)
frames = list(chain.run(until=400.0, every=1000))

fig, axes = plt.subplots(1, len(frames), figsize=(3 * len(frames), 6), sharey=True)
for ax, f in zip(axes, frames):
    x, z = f.positions[:, 0], f.positions[:, 2]
    for xi, zi, a in zip(x, z, chain.radii):
        ax.add_patch(plt.Circle((xi, zi - z.max()), a, color="tab:red" if a > 1 else "tab:blue", alpha=0.6))
    ax.set(title=f"t = {f.time:.0f}", xlim=(x.mean() - 12, x.mean() + 12), ylim=(-60, 5), aspect="equal")
fig.savefig("figure1c.png", dpi=100)
print(f"{len(chain)} beads, t = {chain.time:.1f}: wrote figure1c.png")
