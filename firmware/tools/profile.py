#!/usr/bin/env python3
"""Instruction profile of one firmware binary under QEMU, per step stage.

    python3 firmware/tools/profile.py ELF [STEPS]

Runs ELF on mps2-an386 with one instruction per translation block and an execution
trace (`-singlestep -d exec,nochain`), streamed through a FIFO and counted per program
counter (the trace of 200 steps would be gigabytes on disk). Each counted address is
mapped to its inline chain with `arm-none-eabi-addr2line -i` (LTO inlines the whole
step into `main`), and attributed to a stage: the first frame inside the integrator
(`step_slices`, `overdamped`, `rattle_stable`, ...), or to the standalone function it
lies in. Prints instructions per step (divided by STEPS, default 200) per stage, and
the leaf functions that cost the most.
"""
import collections
import os
import subprocess
import sys
import tempfile

INTEGRATOR = (
    "hydrorattle::integrate::step_slices",
    "hydrorattle::integrate::step",
    "hydrorattle::integrate::overdamped::",
    "hydrorattle::integrate::stable::rattle_stable",
    "hydrorattle::integrate::rattle::",
    "hydrorattle::integrate::springs::",
    "hydrorattle_scene::run",
)


def trace(elf):
    """Executions per program counter."""
    counts = collections.Counter()
    with tempfile.TemporaryDirectory() as d:
        fifo = os.path.join(d, "exec")
        os.mkfifo(fifo)
        qemu = subprocess.Popen(
            ["qemu-system-arm", "-cpu", "cortex-m4", "-machine", "mps2-an386",
             "-nographic", "-semihosting-config", "enable=on,target=native",
             "-icount", "shift=0", "-singlestep", "-d", "exec,nochain", "-D", fifo,
             "-kernel", elf],
            stdout=subprocess.DEVNULL)
        with open(fifo, "rb") as log:
            for line in log:
                # "Trace 0: 0x... [flags/pc/...] symbol"
                lb = line.find(b"[")
                if lb >= 0:
                    counts[line[lb + 10:lb + 18]] += 1
        qemu.wait()
    return counts


def chains(elf, pcs):
    """Inline chain (innermost first) of each address."""
    out = subprocess.run(
        ["arm-none-eabi-addr2line", "-e", elf, "-f", "-i", "-C", "-a"],
        input="\n".join("0x" + p.decode() for p in pcs), capture_output=True,
        text=True, check=True).stdout.splitlines()
    result, cur, i = {}, None, 0
    while i < len(out):
        if out[i].startswith("0x"):
            cur = out[i][2:].encode()
            result[cur] = []
            i += 1
        else:
            result[cur].append(out[i])
            i += 2
    return result


def stage_of(chain):
    outer = list(reversed(chain))
    last = None
    for k, f in enumerate(outer):
        if f.startswith(INTEGRATOR):
            last = k
    if last is None:
        return outer[0] if outer else "?"
    return outer[last + 1] if last + 1 < len(outer) else outer[last] + " (own)"


def short(name):
    name = name.split("<")[0] if not name.startswith("<") else name
    return name.replace("hydrorattle::", "")[:70]


def main():
    elf = sys.argv[1]
    steps = int(sys.argv[2]) if len(sys.argv) > 2 else 200
    counts = trace(elf)
    ch = chains(elf, list(counts))
    stages, leaves = collections.Counter(), collections.Counter()
    for pc, n in counts.items():
        c = ch.get(pc, ["?"])
        stages[short(stage_of(c))] += n
        leaves[short(c[0])] += n
    total = sum(counts.values())
    print(f"{os.path.basename(elf)}: {total} instructions in the whole run; per step:")
    print("\nstage (first frame inside the integrator, or standalone function)")
    for name, n in stages.most_common(25):
        print(f"{n / steps:12.0f}  {100 * n / total:5.1f} %  {name}")
    print("\nleaf function (innermost inlined frame)")
    for name, n in leaves.most_common(25):
        print(f"{n / steps:12.0f}  {100 * n / total:5.1f} %  {name}")


if __name__ == "__main__":
    main()
