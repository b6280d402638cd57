# SPDX-License-Identifier: Apache-2.0
"""`kmx web`: the servo wizard, a local page on 127.0.0.1 (docs/web.md).

The server is aiohttp (Debian: python3-aiohttp); the page is plain HTML,
CSS and JavaScript from kmx/web/, its charts Debian's Chart.js
(libjs-chart.js, served from /usr/share/javascript/chart.js); nothing is
fetched from the internet. Every bus operation runs in one worker thread,
one after the other, so the page's requests never interleave frames on the
bus. A long operation (scan at every baud, rescue, update) is a job the
page polls for its progress.

JSON API (all POST bodies JSON; every answer {"ok": true, ...} or
{"ok": false, "error": one line}):
    POST /api/connect {bus}          open the bus (any kmx bus spec)
    POST /api/scan {all_bauds}       job: servos with ID, baud, model, firmware, status in words
    GET  /api/job                    the running or last job: progress 0..1, lines, result
    GET  /api/servo/ID/registers     the control table: name, address, value, unit, range, enum words
    POST /api/servo/ID/set {name, value}   checked (type, range, product, angle limits), read back
    POST /api/servo/ID/torque {state}      on, off, brake
    POST /api/servo/ID/move {angle, time_ms}  0x65;  POST /api/servo/ID/jog {angle}  0x68
    GET  /api/live?ids=1,2,3         one sample by 0x82: position, speed, current, pwm, temperature, voltage, status
    POST /api/live/start {ids, period_ms}, /api/live/stop; GET /api/live/data?since=SEQ: samples taken
                                     by the server on that schedule, the rate reached and what one sample takes
    GET  /api/servo/ID/faults        the fault log
    POST /api/servo/ID/set-id {new}  POST /api/servo/ID/set-baud {baud}   POST /api/rescue (job)
    POST /api/update {ids, image}    job: the firmware update (kmx/update.py), per-servo progress
    POST /api/servo/ID/bench {preset} or {key, value}   the emulated bench (kmx/bench.py, --inject-dir)
    GET  /api/servo/ID/protection    status and 0x36 in words, temperature, voltage: a trip and its release
"""

import argparse
import asyncio
import concurrent.futures
import contextlib
import io
import os
import re
import signal
import struct
import sys
import time

from . import baud as kbaud
from . import bench as kbench
from . import cli
from . import faultlog
from . import frame as fr
from . import update as kupdate
from .bus import Bus
from .deps import import_debian
from .errors import KmxError
from .products import Limits
from .registers import RegisterMap, Registers

HERE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "web")
CHART_JS = "/usr/share/javascript/chart.js"
LIVE_KEEP = 2000  # samples kept for the page (100 s at 20 Hz)
RESCUE_BOOT_S = 20.0  # the rescued servo's new image answers a super-ID ping within this (a starved
# emulator works through a backlog of broadcast frames for seconds after the last one was sent)
RESCUE_PASSES = 2  # blind rescue passes before the page says no servo came back
UPDATE_PASSES = 6  # a pass that loses a servo's STATUS starts again from ENTER
LIVE = ("position", "speed", "current", "pwm", "temperature", "voltage", "status")
ENUM = re.compile(r"^(\d+) (?:= )?([a-z][^,;]*)$")


def enum_words(reg):
    """{code: words} of a coded one-byte register, from its description
    ("0 auto, 1 servo only, 2 motor only"), or None when it is not a list
    of codes."""
    f = reg.fields[0]
    if len(reg.fields) != 1 or f["unit"] or f["type"] != "u8":
        return None
    parts = [ENUM.match(p.strip()) for p in re.split(r"[,;]", reg.description)]
    if len(parts) < 2 or not all(parts):
        return None
    return {int(m.group(1)): m.group(2).strip() for m in parts}


def register_row(reg, value):
    """One control-table row: what the page shows and edits."""
    fields = [{"unit": f["unit"], "min": f.get("min"), "max": f.get("max"), "scale": f["scale"],
               "optional": bool(f.get("optional"))} for f in reg.fields]
    return {"name": reg.name, "address": "0x%02X" % reg.address, "title": reg.title,
            "access": reg.access, "description": reg.description, "fields": fields,
            "enum": enum_words(reg), "value": None if value is None else str(value),
            "number": None if value is None or not isinstance(value.value, (int, float)) else value.value}


class Job:
    """A long operation's state, read by the page while it runs."""

    def __init__(self, kind):
        self.kind, self.progress, self.lines, self.result = kind, 0.0, [], None
        self.done, self.error, self.servos = False, None, {}

    def as_dict(self):
        return {"kind": self.kind, "progress": self.progress, "lines": self.lines[-200:], "done": self.done,
                "error": self.error, "result": self.result, "servos": self.servos}


class WebUpdater(kupdate.Updater):
    """The update pass with its progress for the page: blocks sent this pass
    and each servo's state from every STATUS it answers."""

    def __init__(self, job, *args, **kw):
        super().__init__(*args, **kw)
        self.job, self.blocks_sent = job, 0

    def send(self, data, answers=0, timeout=None):
        if len(data) > 5 and data[4] == kupdate.CMD and data[5] == kupdate.WRITE:
            self.blocks_sent += 1
            self.job.progress = min(0.95, 0.1 + 0.8 * self.blocks_sent / max(1, self.blocks))
        return super().send(data, answers, timeout)

    def status(self, dev_id, first=0):
        st = super().status(dev_id, first)
        if st is not None and dev_id in self.job.servos:
            self.job.servos[dev_id].update(state=kupdate.STATES.get(st["state"], st["state"]),
                                           received=st["received"], blocks=st["blocks"])
        return st


class Wizard:
    """The bus and what the page asks of it; every method runs in the bus thread."""

    def __init__(self, spec=None, inject_dir=None):
        self.bench = kbench.Bench(inject_dir) if inject_dir else None
        self.bus = self.regs = None
        self.map = RegisterMap.load()
        self.job = None
        self.t0 = time.monotonic()
        self.spec, self.note = spec, None
        if spec:
            try:
                self.connect({"bus": spec})
            except KmxError as e:  # the page offers to connect to another
                self.note = str(e)

    def connect(self, body):
        """Opens the bus the page names (closing the one before)."""
        if self.bus is not None:
            self.bus.close()
            self.bus = None
        self.bus = Bus(body["bus"], timeout=0.1, retries=2)
        self.regs = Registers(self.bus, self.map)
        self.spec = self.bus.transport.spec
        return self.state()

    def state(self):
        """What the page shows first: the bus, or why there is none."""
        return {"bus": self.bus.transport.spec if self.bus else None, "spec": self.spec, "note": self.note,
                "baud": self.bus.baud if self.bus else None,
                "can_set_baud": bool(self.bus and getattr(self.bus.transport, "can_set_baud", False)),
                "bench": self.bench_state()}

    def bench_state(self):
        """The bench section: its servos and presets, or why there is none."""
        kind = getattr(self.bus.transport, "kind", None) if self.bus else None
        if kind in ("serial", "hwgrep"):
            return {"servos": [], "why": "a real bus: the supply, heat and load are your bench's own "
                                         "(scenarios exist on the emulated bus only)"}
        if self.bench is None:
            return {"servos": [], "why": "no bench: start the emulated bus with sim/bus/servo-bus "
                                         "--inject-dir DIR and kmx web with --inject-dir DIR"}
        ids = self.bench.servos()
        if not ids:
            return {"servos": [], "why": "no bench: no servo sockets in %s (servo-bus --inject-dir %s, "
                                         "host-sim backend)" % (self.bench.dir, self.bench.dir)}
        return {"servos": ids, "why": None, "keys": {k: list(v) for k, v in kbench.KEYS.items()},
                "presets": {k: v[0] for k, v in kbench.PRESETS.items()}}

    def bench_inject(self, dev_id, body):
        """A preset or one KEY VALUE on dev_id's emulated bench: what was applied."""
        why = self.bench_state()["why"]
        if why:
            raise KmxError(why)
        if "preset" in body:
            if body["preset"] not in kbench.PRESETS:
                raise KmxError("bench: no preset %r (%s)" % (body["preset"], ", ".join(kbench.PRESETS)))
            events = kbench.PRESETS[body["preset"]][1]
        else:
            events = [(str(body["key"]), int(body["value"]))]
        done = [self.bench.inject(dev_id, key, value)[3:] for key, value in events]
        return {"applied": done}

    def protection(self, dev_id):
        """What the page shows while a protection trips and releases: the
        status byte and 0x36 in words, temperature and voltage."""
        self.need_bus()
        status = self.bus.ping(dev_id)
        flags = self.regs.get(dev_id, "prot_flags").value
        names = [w for bit, w in ((8, "stall"), (4, "temperature"), (2, "current"), (1, "voltage")) if flags & bit]
        return {"status": ", ".join(fr.status_words(status)), "status_byte": status, "prot_flags": flags,
                "protecting": ", ".join(names) or "none",
                "temperature": str(self.regs.get(dev_id, "temperature")),
                "voltage": str(self.regs.get(dev_id, "voltage"))}

    def need_bus(self):
        if self.bus is None:
            raise KmxError("no bus open: connect to one first")

    def scan(self, job, body):
        """The servos on the bus (at every standard baud with all_bauds)."""
        self.need_bus()
        if body.get("all_bauds"):
            kbaud._need_baud_control(self.bus, "scan at every baud")
            rows = []
            for n, b in enumerate(kbaud.STANDARD_BAUDS):
                job.lines.append("scanning at %d baud" % b)
                rows += kbaud.scan_all_bauds(self.bus, self.regs, None, (b,))
                job.progress = (n + 1) / len(kbaud.STANDARD_BAUDS)
            return [{"id": r[0], "baud": r[1], "model": r[2], "firmware": r[3], "status": r[4]} for r in rows]
        job.lines.append("super-ID ping on %s" % self.bus.transport.spec)
        found = self.bus.scan()
        job.progress = 0.3
        out = []
        for n, (dev_id, status) in enumerate(found):
            row = {"id": dev_id, "baud": self.bus.baud, "status": ", ".join(fr.status_words(status))}
            for key, name in (("model", "product_info"), ("firmware", "firmware_version")):
                try:
                    row[key] = str(self.regs.get(dev_id, name))
                except KmxError:
                    row[key] = "?"
            out.append(row)
            job.progress = 0.3 + 0.7 * (n + 1) / len(found)
            job.lines.append("found ID %d: %s" % (dev_id, row["model"]))
        return out

    def registers(self, dev_id):
        """The control table of one servo, every readable register read."""
        self.need_bus()
        limits = Limits(self.bus, self.map)
        model, numbers = limits.product(dev_id)
        rows = []
        for reg in self.map:
            value = self.regs.get(dev_id, reg.address) if reg.readable else None
            row = register_row(reg, value)
            bound = limits.table["bounds"].get("0x%02X" % reg.address)
            if numbers is not None and bound is not None:  # "product" -> this servo's model's numbers
                for f in row["fields"]:
                    f["min"] = limits._bound(numbers, bound[0]) if f["min"] == "product" else f["min"]
                    f["max"] = limits._bound(numbers, bound[1]) if f["max"] == "product" else f["max"]
            rows.append(row)
        return {"registers": rows, "model": model}

    def set(self, dev_id, body):
        """A register by name, value in units; read back when readable."""
        self.need_bus()
        reg = self.map.find(body["name"])
        value = body["value"]
        data = reg.encode(value)
        self.regs.check(dev_id, reg, data)
        self.bus.write(dev_id, reg.address, data)
        status = self.bus.ping(dev_id)
        if status & 0x20:
            self.bus.check_update_mode(dev_id)
        if status & 0x60:
            raise KmxError("ID %d refused %s = %s: status 0x%02X (%s)" % (
                dev_id, reg.name, value, status, ", ".join(fr.status_words(status))))
        back = str(self.regs.get(dev_id, reg.address)) if reg.readable else str(reg.decode(data))
        return {"name": reg.name, "value": back}

    def torque(self, dev_id, body):
        """Torque on, off or brake (0x64); the state read back in words."""
        state = body.get("state")
        if state not in cli.TORQUE:
            raise KmxError("torque: %r is not a state; give one of %s" % (state, ", ".join(cli.TORQUE)))
        r = self.set(dev_id, {"name": "torque_switch", "value": cli.TORQUE[state]})
        words = cli.TORQUE_WORDS.get(int(r["value"])) if r["value"].isdigit() else None
        return dict(r, value="%s (%s)" % (r["value"], words) if words else r["value"])

    def move(self, dev_id, body):
        value = [body["angle"]] + ([body["time_ms"]] if body.get("time_ms") else [])
        return self.set(dev_id, {"name": "move_time", "value": value})

    def jog(self, dev_id, body):
        return self.set(dev_id, {"name": "interpolate", "value": body["angle"]})

    def live(self, ids):
        """One sample of every servo in ids: each register by one 0x82 (0x02
        for a servo without it, cli.monitor_sample)."""
        self.need_bus()
        t = time.monotonic() - self.t0
        sample = cli.monitor_sample(self.bus, self.regs, LIVE, ids)
        out = {}
        for i in ids:
            *values, status = sample[i]
            out[i] = dict(zip(LIVE[:-1], (v.value for v in values)))
            out[i]["status"] = ", ".join(fr.status_words(status.raw[0]))
        return {"t": t, "took": time.monotonic() - self.t0 - t, "servos": out}

    def faults(self, dev_id):
        """The fault log with the last reset's cause."""
        self.need_bus()
        events, held, kept = faultlog.read_summary(self.bus, dev_id)
        source, cause = faultlog.read_boot(self.bus, dev_id)
        rows = [dict(zip(faultlog.ROW_HEADER, map(str, e.row(i))))
                for i, e in enumerate(faultlog.read_entries(self.bus, dev_id, held))]
        return {"events": events, "held": held, "kept": kept, "reset": cause, "userdata": source, "entries": rows}

    def _cli(self, fn, **kw):
        """A kmx command's function on this bus; its printed lines."""
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            fn(self.bus, self.regs, argparse.Namespace(**kw))
        return {"lines": out.getvalue().splitlines()}

    def set_id(self, dev_id, body):
        self.need_bus()
        return self._cli(cli.cmd_set_id, id=dev_id, new=int(body["new"]))

    def set_baud(self, dev_id, body):
        self.need_bus()
        return self._cli(kbaud.cmd_set_baud, id=dev_id, baud=kbaud.parse_baud(str(body["baud"])))

    def rescue(self, job, body):
        self.need_bus()
        kbaud._need_baud_control(self.bus, "rescue")
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            kbaud.cmd_rescue(self.bus, self.regs, argparse.Namespace(scan_ms=None))
        job.lines += out.getvalue().splitlines()
        return {"lines": out.getvalue().splitlines()}

    def update(self, job, body):
        """The firmware update of body["ids"] (or rescue) with body["image"]
        (bytes, base64 in the request); the end state per servo."""
        self.need_bus()
        image = body["image"]
        ids = [kupdate.BCAST] if body.get("rescue") else [int(i) for i in body["ids"]]
        for i in ids:
            job.servos[i] = {"state": "waiting", "received": 0, "blocks": 0}
        path = body["path"]
        kupdate.load_image(path)
        up = WebUpdater(job, self.bus, ids, image, job.lines.append)
        up.baud = self.bus.baud
        if not body.get("rescue"):
            for i, v in kupdate.preflight(up, ids, self.bus.transport.spec).items():
                job.lines.append("ID %d: 0x0C = 0x%08X" % (i, v))
                job.servos[i]["state"] = "checked: 0x%08X" % v
        new = struct.unpack_from("<I", image, 12)[0]
        if body.get("rescue"):
            return self.rescue_update(up, job, new)
        a = argparse.Namespace(rescue=False, rounds=4, one_by_one=False, prog="kmx web", resets=0, restarts=0)
        done = kupdate.run_groups(up, a, ids, [], UPDATE_PASSES, job.lines.append)
        if done is None:
            raise KmxError("the update gave up after %d passes: the servos wait in their bootloaders; "
                           "run it again" % UPDATE_PASSES)
        ok = kupdate.check_result(up, a, done, new, job.lines.append)
        for i in done:
            job.servos[i]["state"] = "updated" if ok else "NOT updated"
        return {"updated": done, "ok": ok}

    def rescue_update(self, up, job, new):
        """Blind rescue passes (everything broadcast, the servo alone on the
        bus) until a servo answers a super-ID ping, RESCUE_PASSES at most: a
        pass spoiled on a loaded machine (a frame lost, a starved emulator
        behind the pass's fixed waits) costs a pass, not the rescue. The end
        state is the 0x0C of the servo that answers, not what was sent."""
        row = job.servos[kupdate.BCAST]
        found = []
        for n in range(RESCUE_PASSES):
            job.lines.append("rescue pass %d: every frame broadcast" % (n + 1))
            row["state"] = "pass %d" % (n + 1)
            up.rescue_pass(2)
            found = self.rescued_ids(up)
            if found:
                break
        if len(found) != 1:
            row["state"] = "NOT found: %s a super-ID ping after %d passes (the servo rescued is alone on " \
                           "the bus)" % ("IDs %s answer" % ", ".join(map(str, found)) if found else "no servo answers",
                                         RESCUE_PASSES)
            job.lines.append(row["state"])
            return {"updated": [], "ok": False}
        dev_id = found[0]
        v = up.version(dev_id)
        good = v is not None and (v & 0xFFFFFF) == (new & 0xFFFFFF)
        row["state"] = "%s: ID %d runs 0x0C = %s" % ("updated" if good else "NOT updated", dev_id,
                                                     "0x%08X" % v if v is not None else "(no answer)")
        job.lines.append("rescued servo: " + row["state"])
        return {"updated": [dev_id] if good else [], "ok": good}

    def rescued_ids(self, up):
        """The IDs answering a super-ID ping within RESCUE_BOOT_S of a rescue
        pass, the pass's last frames sent again between tries."""
        found = []
        end = time.monotonic() + RESCUE_BOOT_S
        while time.monotonic() < end:
            # a second of listening: a starved emulator answers after its slot
            found = sorted({i for i, _ in self.bus.scan(timeout=max(1.0, self.bus.scan_window()))})
            if found:
                break
            # the last frames again (an application answers them "not supported"): a
            # bootloader still busy with a COMMIT or an erase when they came now takes them
            for sub, params in ((kupdate.VERIFY, b""), (kupdate.COMMIT, b""), (kupdate.START, kupdate.START_MAGIC)):
                up.send(kupdate.frame(kupdate.BCAST, sub, params))
                time.sleep(0.5)
        return found


class Server:
    """aiohttp routes onto a Wizard, its calls in one bus thread."""

    def __init__(self, wizard):
        self.web = import_debian("aiohttp.web", "python3-aiohttp", "kmx web needs aiohttp")
        self.wizard = wizard
        self.pool = concurrent.futures.ThreadPoolExecutor(max_workers=1, thread_name_prefix="kmx-bus")
        self.live_ids, self.live_samples, self.live_seq, self.live_error = None, [], 0, None
        self.live_asked = None  # samples per second asked by /api/live/start

    async def call(self, fn, *args):
        """fn(*args) in the bus thread: {"ok": true, ...result} or {"ok": false, "error"}."""
        loop = asyncio.get_running_loop()
        try:
            result = await loop.run_in_executor(self.pool, lambda: fn(*args))
        except KmxError as e:
            return self.web.json_response({"ok": False, "error": str(e)})
        except (KeyError, ValueError, TypeError) as e:
            return self.web.json_response({"ok": False, "error": "bad request: %s" % e})
        return self.web.json_response(dict({"ok": True}, **(result or {})))

    def start_job(self, kind, fn, body):
        """Runs fn(job, body) in the bus thread; the page polls /api/job."""
        job = Job(kind)
        self.wizard.job = job

        def run():
            try:
                job.result = fn(job, body)
            except KmxError as e:
                job.error = str(e)
                job.lines.append(str(e))
            except Exception as e:  # a bug must reach the page as words, not kill the thread
                job.error = "internal error: %r" % e
            finally:
                job.progress, job.done = 1.0, True
        self.pool.submit(run)
        return self.web.json_response({"ok": True, "job": kind})

    def routes(self):
        """The app: the page, Chart.js, the API."""
        web = self.web
        app = web.Application(client_max_size=4 * 1024 * 1024)
        r = app.router
        r.add_get("/", lambda req: web.FileResponse(os.path.join(HERE, "index.html")))
        r.add_static("/static/", HERE)
        if os.path.isdir(CHART_JS):
            r.add_static("/chart.js/", CHART_JS)
        r.add_post("/api/connect", self.h_connect)
        r.add_get("/api/state", self.h_state)
        r.add_post("/api/scan", self.h_scan)
        r.add_get("/api/job", self.h_job)
        r.add_get("/api/live", self.h_live)
        r.add_post("/api/live/start", self.h_live_start)
        r.add_post("/api/live/stop", self.h_live_stop)
        r.add_get("/api/live/data", self.h_live_data)
        r.add_post("/api/rescue", self.h_rescue)
        r.add_post("/api/update", self.h_update)
        r.add_get("/api/servo/{id}/registers", self.h_servo_get)
        r.add_get("/api/servo/{id}/faults", self.h_servo_get)
        r.add_get("/api/servo/{id}/protection", self.h_servo_get)
        r.add_post("/api/servo/{id}/{what}", self.h_servo_post)
        return app

    async def body(self, request):
        try:
            return await request.json()
        except ValueError:
            return {}

    async def h_connect(self, request):
        return await self.call(self.wizard.connect, await self.body(request))

    async def h_state(self, request):
        return self.web.json_response(dict({"ok": True}, **self.wizard.state()))

    async def h_scan(self, request):
        return self.start_job("scan", self.wizard.scan, await self.body(request))

    async def h_rescue(self, request):
        return self.start_job("rescue", self.wizard.rescue, await self.body(request))

    async def h_job(self, request):
        job = self.wizard.job
        return self.web.json_response({"ok": True, "job": job.as_dict() if job else None})

    async def h_live(self, request):
        try:
            ids = [int(i) for i in request.query.get("ids", "").split(",") if i]
        except ValueError:
            return self.web.json_response({"ok": False, "error": "ids: a comma-separated list of IDs"})
        return await self.call(self.wizard.live, ids)

    async def sampler(self, ids, period):
        """While live: one sample of ids every `period` s in the bus thread
        (other requests take their turn between samples), kept for the page."""
        loop = asyncio.get_running_loop()
        next_at = loop.time()
        while self.live_ids == ids:
            try:
                sample = await loop.run_in_executor(self.pool, self.wizard.live, ids)
                self.live_seq += 1
                sample["seq"] = self.live_seq
                self.live_samples.append(sample)
                del self.live_samples[:-LIVE_KEEP]
            except KmxError as e:
                self.live_error = str(e)
            next_at = max(next_at + period, loop.time())
            await asyncio.sleep(next_at - loop.time())

    async def h_live_start(self, request):
        """{ids, period_ms}: sampling starts (20 Hz by default); the page reads /api/live/data."""
        body = await self.body(request)
        try:
            ids = [int(i) for i in body["ids"]]
            period = max(0.01, float(body.get("period_ms", 50)) / 1000.0)
        except (KeyError, ValueError, TypeError):
            return self.web.json_response({"ok": False, "error": "live: give ids and period_ms"})
        self.live_ids, self.live_error, self.live_asked = ids, None, 1.0 / period
        self.live_task = asyncio.get_running_loop().create_task(self.sampler(ids, period))
        return self.web.json_response({"ok": True, "ids": ids, "period_ms": period * 1000})

    async def h_live_stop(self, request):
        self.live_ids = None
        return self.web.json_response({"ok": True})

    async def h_live_data(self, request):
        """The samples after ?since=SEQ, with the measured sample rate, the
        rate asked and the median time one sample takes (the last 20): below
        the rate asked, a sample that takes longer than the period says the
        bus or the host is the limit, not the schedule."""
        since = int(request.query.get("since", "0") or 0)
        new = [x for x in self.live_samples if x["seq"] > since]
        recent = self.live_samples[-20:]
        rate = took = None
        if len(recent) > 2:
            rate = (len(recent) - 1) / (recent[-1]["t"] - recent[0]["t"])
            took = sorted(x["took"] for x in recent)[len(recent) // 2]
        return self.web.json_response({"ok": self.live_error is None, "error": self.live_error,
                                       "samples": new, "rate": rate, "took": took, "asked": self.live_asked})

    def servo_id(self, request):
        dev_id = int(request.match_info["id"])
        if not 0 <= dev_id <= fr.ID_MAX:
            raise ValueError("servo ID %d is outside 0..%d" % (dev_id, fr.ID_MAX))
        return dev_id

    async def h_servo_get(self, request):
        what = request.path.rsplit("/", 1)[1]
        fn = {"registers": self.wizard.registers, "faults": self.wizard.faults,
              "protection": self.wizard.protection}[what]
        try:
            dev_id = self.servo_id(request)
        except ValueError as e:
            return self.web.json_response({"ok": False, "error": str(e)})
        return await self.call(fn, dev_id)

    async def h_servo_post(self, request):
        w = self.wizard
        fn = {"set": w.set, "torque": w.torque, "move": w.move, "jog": w.jog, "set-id": w.set_id,
              "set-baud": w.set_baud, "bench": w.bench_inject}.get(request.match_info["what"])
        if fn is None:
            return self.web.json_response({"ok": False, "error": "no such action"}, status=404)
        try:
            dev_id = self.servo_id(request)
        except ValueError as e:
            return self.web.json_response({"ok": False, "error": str(e)})
        return await self.call(fn, dev_id, await self.body(request))

    async def h_update(self, request):
        """multipart: ids or rescue, and the image file."""
        reader = await request.post()
        upload = reader.get("image")
        if upload is None or not hasattr(upload, "file"):
            return self.web.json_response({"ok": False, "error": "choose an update image (.kmfw) first"})
        data = upload.file.read()
        path = os.path.join(self.tmpdir, "upload.kmfw")
        with open(path, "wb") as f:
            f.write(data)
        body = {"image": data, "path": path, "rescue": reader.get("rescue") == "1",
                "ids": [i for i in str(reader.get("ids", "")).split(",") if i.strip()]}
        try:
            kupdate.load_image(path)
            if not body["rescue"]:
                kupdate.ids_arg(",".join(body["ids"]))
        except kupdate.Refused as e:
            return self.web.json_response({"ok": False, "error": e.args[0]})
        except argparse.ArgumentTypeError as e:
            return self.web.json_response({"ok": False, "error": "IDs: %s" % e})
        return self.start_job("update", self.wizard.update, body)


def serve(spec, host, port, ready=None, inject_dir=None):
    """Runs the page on host:port until Ctrl-C; ready(url) once it listens."""
    import tempfile
    server = Server(Wizard(spec, inject_dir))
    web = server.web
    with tempfile.TemporaryDirectory() as tmp:
        server.tmpdir = tmp

        async def main():
            stop = asyncio.Event()
            # Ctrl-C sets stop between callbacks: raised inside one (aiohttp accepting or
            # closing a connection), KeyboardInterrupt came out as a traceback
            with contextlib.suppress(NotImplementedError, RuntimeError, ValueError):  # no loop signals here
                asyncio.get_running_loop().add_signal_handler(signal.SIGINT, stop.set)
            runner = web.AppRunner(server.routes(), access_log=None)
            await runner.setup()
            site = web.TCPSite(runner, host, port)
            await site.start()
            bound = site._server.sockets[0].getsockname()[1]
            url = "http://%s:%d/" % (host, bound)
            (ready or print)(url)
            try:
                await stop.wait()
            finally:
                await runner.cleanup()
        try:
            asyncio.run(main())
        finally:
            server.pool.shutdown(wait=False, cancel_futures=True)
            if server.wizard.bus is not None:
                server.wizard.bus.close()


def cmd_web(args):
    """kmx web: serve the page; prints its address."""
    if args.host not in ("127.0.0.1", "localhost", "::1") and not args.any_host:
        raise KmxError("kmx web serves on this machine only (127.0.0.1); --any-host to serve %s "
                       "(anyone who reaches it drives the servos)" % args.host)
    spec = args.bus

    def ready(url):
        print("kmx web: open %s in a browser (Ctrl-C stops it)" % url, flush=True)
    try:
        serve(spec, args.host, args.port, ready, getattr(args, "inject_dir", None))
    except KeyboardInterrupt:  # Ctrl-C before the page's loop took it over
        pass
    except OSError as e:
        raise KmxError("cannot serve on %s:%d: %s" % (args.host, args.port, e.strerror or e)) from None
    print("kmx web: stopped", flush=True)  # the way to stop it: Ctrl-C
    return 0


if __name__ == "__main__":
    sys.exit(cli.main(["web"] + sys.argv[1:]))
