# SPDX-License-Identifier: Apache-2.0
"""Traces to pictures: samples position, speed and current of one servo at
a fixed period (optionally right after a step command) and draws them to a
PNG with Debian's python3-matplotlib (a MissingPackage error naming it when
absent)."""

import time

from .deps import import_debian

SETTLE_DEG = 0.5  # "reached": within this of the target from then on


class Trace:
    def __init__(self, dev_id, target=None):
        self.dev_id = dev_id
        self.target = target
        self.t = []
        self.position = []
        self.speed = []
        self.current = []

    def __len__(self):
        return len(self.t)

    def settled_at(self):
        """Seconds after which the position stays within SETTLE_DEG of the
        target, or None (no target, or never)."""
        if self.target is None:
            return None
        at = None
        for t, p in zip(self.t, self.position):
            if abs(p - self.target) <= SETTLE_DEG:
                at = t if at is None else at
            else:
                at = None
        return at


def record(bus, regs, dev_id, seconds, interval_s, t0=None, target=None):
    """Samples 0x46, 0x47, 0x48 every interval_s for `seconds` (from t0)."""
    reg = [regs.map.find(n) for n in ("position", "speed", "current")]
    trace = Trace(dev_id, target)
    t0 = time.monotonic() if t0 is None else t0
    nxt = time.monotonic()
    while True:
        f = bus.read_frame(dev_id, reg[0].address)
        t = f.time - t0
        if t > seconds:
            return trace
        trace.t.append(t)
        trace.position.append(reg[0].decode(f.params).value)
        trace.speed.append(reg[1].decode(bus.read(dev_id, reg[1].address)).value)
        trace.current.append(reg[2].decode(bus.read(dev_id, reg[2].address)).value)
        nxt += interval_s
        time.sleep(max(0.0, nxt - time.monotonic()))


def render(trace, path, title):
    """Writes the trace as a PNG: position, speed and current over time."""
    matplotlib = import_debian("matplotlib", "python3-matplotlib", "plot needs matplotlib")
    matplotlib.use("Agg")  # files only: no display needed
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(3, 1, sharex=True, figsize=(8, 7))
    axes[0].plot(trace.t, trace.position, label="position")
    if trace.target is not None:
        axes[0].axhline(trace.target, color="grey", linestyle="--", label="target")
        axes[0].legend(loc="lower right")
    axes[0].set_ylabel("position (°)")
    axes[1].plot(trace.t, trace.speed, color="tab:orange")
    axes[1].set_ylabel("speed (°/s)")
    axes[2].plot(trace.t, trace.current, color="tab:red")
    axes[2].set_ylabel("current (mA)")
    axes[2].set_xlabel("time (s)")
    for ax in axes:
        ax.grid(True, alpha=0.3)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
