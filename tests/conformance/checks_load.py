# SPDX-License-Identifier: Apache-2.0
"""Sustained load: --load N mixed request frames on every servo under test
(pings, reads, writes, super-ID pings and reads, sync write rounds, 0x83),
every answer checked against a model of what the master wrote; 0 errors.
Prints throughput and latency percentiles (send to last expected answer, on
this host: a figure, not a pass/fail bound)."""
import random
import time

import spec
from ctx import Fail, check, hexs
from wire import fr


def _pct(sorted_ts, p):
    if not sorted_ts:
        return float("nan")
    return sorted_ts[min(len(sorted_ts) - 1, int(p / 100.0 * len(sorted_ts)))]


@check("load.mixed", "§3 (all commands), §4",
       "N mixed transactions (--load, default 100000): every answer as the model says, no bad "
       "frame; throughput and latency p50/p95/p99/max printed")
def load_mixed(ctx):
    ids = ctx.ids
    target = ctx.opts.load
    rng = random.Random(20261123)
    saved = {i: ctx.snapshot(i, [0x11, 0x5B, 0x64]) for i in ids}
    model_5b, model_64 = {}, {}
    lim = {}
    errors = []
    kinds = {}  # error kind -> count
    lat = {}
    bad0 = ctx.wire.bad_frames

    def err(msg, kind):
        errors.append(msg)
        kinds[kind] = kinds.get(kind, 0) + 1
        if kinds.get("missing answer", 0) >= 100:  # the bus is gone: stop
            raise Fail("%d errors, first: %s" % (len(errors), "; ".join(errors[:5])))

    def timed(kind, frame, n):
        t = time.perf_counter()
        r = ctx.wire.transact(frame, n, ctx.timeout)
        took = time.perf_counter() - t
        lat.setdefault(kind, []).append(took)
        if len(r) != n:
            err("%s %s: %d of %d answers" % (kind, hexs(frame), len(r), n), "missing answer")
        return r, took

    try:
        for i in ids:
            ctx.write_ok(i, 0x11, bytes([saved[i][0x11][0] | 0x08]))
            lim[i] = min(1000, ctx.read_int(i, 0x13))
            model_5b[i] = ctx.read_int(i, 0x5B)
            model_64[i] = ctx.read_int(i, 0x64)
        sent = 0
        t0 = time.perf_counter()
        while sent < target:
            i = rng.choice(ids)
            k = rng.random()
            if k < 0.25:
                r, _ = timed("ping", fr.ping(i), 1)
                if r and not (r[0].id == i and r[0].is_status and not r[0].status & spec.BITS_56):
                    err("ping %d answered %s" % (i, hexs(r[0].to_bytes())), "wrong answer")
                sent += 1
            elif k < 0.55:
                addr = rng.choice((0x0B, 0x5B, 0x64, 0x46, 0x01))
                r, _ = timed("read", fr.read(i, addr), 1)
                if r:
                    f = r[0]
                    want = {0x0B: spec.PROTOCOL_VERSION, 0x5B: model_5b[i], 0x64: model_64[i]}.get(addr)
                    ok = (f.id == i and not f.is_status and f.addr == addr and
                          len(f.params) in spec.BY_ADDR[addr].lengths)
                    if ok and want is not None:
                        ok = spec.to_int(f.params) == want
                    if not ok:
                        err("read 0x%02X of %d answered %s, model %s" % (addr, i, hexs(f.to_bytes()), want),
                            "wrong answer")
                sent += 1
            elif k < 0.75:
                v = rng.randint(0, lim[i])
                r, _ = timed("write", fr.write(i, 0x5B, spec.u16(v)), 1)
                if r and not (r[0].id == i and r[0].is_status and not r[0].status & spec.BITS_56):
                    err("write 0x5B=%d to %d answered %s" % (v, i, hexs(r[0].to_bytes())), "wrong answer")
                model_5b[i] = v
                sent += 1
            elif k < 0.80:
                frame = fr.ping(spec.ID_SUPER) if rng.random() < 0.5 else fr.read(spec.ID_SUPER, 0x5B)
                r, took = timed("super", frame, len(ids))
                if [f.id for f in r] != sorted(ids)[:len(r)]:
                    err("super ID: answer order %s in %.1f ms" % ([f.id for f in r], took * 1e3),
                        "super-ID slot order")
                for f in r:
                    if not f.is_status and f.id in model_5b and spec.to_int(f.params) != model_5b[f.id]:
                        err("super read 0x5B of %d: %s, model %d" % (f.id, hexs(f.params), model_5b[f.id]),
                            "wrong answer")
                sent += 1
            elif k < 0.90:
                for j in ids:
                    v = rng.randint(0, lim[j])
                    ctx.send(fr.encode_command(j, 0x04, 0x5B, spec.u16(v)))
                    model_5b[j] = v
                ctx.send(fr.encode_command(spec.ID_BROADCAST, 0x84))
                sent += len(ids) + 1
            else:
                vals = {j: rng.randint(0, 1) for j in ids}
                params = bytes([1]) + b"".join(bytes([j, vals[j]]) for j in ids)
                ctx.send(fr.encode_command(spec.ID_BROADCAST, 0x83, 0x64, params))
                model_64.update(vals)
                sent += 1
        wall = time.perf_counter() - t0
        # the unanswered frames at the end are checked too
        for i in ids:
            if ctx.read_int(i, 0x5B) != model_5b[i] or ctx.read_int(i, 0x64) != model_64[i]:
                err("servo %d: final 0x5B/0x64 differ from the model" % i, "wrong answer")
            if ctx.status(i) & spec.BITS_56:
                err("servo %d: status bits 5/6 set at the end" % i, "status bits")
        bad = ctx.wire.bad_frames - bad0
        if bad:
            err("%d frames with a bad checksum or length" % bad, "bad frame")
        answered = sorted(t for ts in lat.values() for t in ts)
        print("# load: %d transactions (request frames) on servos %s in %.1f s: %.0f/s, %d errors%s"
              % (sent, ",".join(map(str, ids)), wall, sent / wall, len(errors),
                 "".join(", %s %d" % kv for kv in sorted(kinds.items()))))
        for e in errors[:10]:
            print("# load: error: %s" % e)
        for kind, ts in sorted(lat.items()) + [("all answered", answered)]:
            ts = sorted(ts)
            print("# load: %-12s n=%-6d latency ms p50 %.2f p95 %.2f p99 %.2f max %.2f"
                  % (kind, len(ts), _pct(ts, 50) * 1e3, _pct(ts, 95) * 1e3, _pct(ts, 99) * 1e3,
                     ts[-1] * 1e3 if ts else float("nan")))
        if errors:
            raise Fail("%d errors: %s" % (len(errors), "; ".join(errors[:5])))
    finally:
        for i in ids:
            ctx.level.pop(i, None)
            ctx.restore(i, saved[i])
