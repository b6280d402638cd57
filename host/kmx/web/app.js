// SPDX-License-Identifier: Apache-2.0
// kmx web: the page's behaviour. Talks to host/kmx/web.py's JSON API only.
"use strict";

const $ = (id) => document.getElementById(id);
const kmx = { servos: [], charts: {}, live: false, samples: 0, t0: null };
window.kmx = kmx; // for the browser tests (tests/tools/kmx_web_check.py)
const QUANTITIES = [["position", "°"], ["speed", "°/s"], ["current", "mA"], ["pwm", "‰"],
                    ["temperature", "°C"], ["voltage", "V"]];
const COLORS = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#17becf", "#e377c2"];
const KEEP = 300; // points per line

// One API call: the JSON answer ({ok: true, ...} or {ok: false, error}).
async function api(path, body) {
  const opts = body === undefined ? {} : { method: "POST", headers: { "Content-Type": "application/json" },
                                           body: JSON.stringify(body) };
  try {
    const r = await fetch(path, opts);
    return await r.json();
  } catch (e) {
    return { ok: false, error: "the kmx web server does not answer (" + e.message + ")" };
  }
}

// A message under a section: green for done, red for a refusal.
function say(id, text, ok) {
  const el = $(id);
  el.textContent = text;
  el.className = "msg " + (ok ? "ok" : "error");
}

function currentId() { return parseInt($("servo-id").value, 10); }

function showState(st) {
  $("busline").textContent = st.bus ? "bus " + st.bus : "not connected" + (st.note ? ": " + st.note : "");
  if (st.spec && !$("bus").value) $("bus").value = st.spec;
  if (st.bench) showBench(st.bench);
}

// The bench section: enabled on an emulated bus with --inject-dir, else the reason.
function showBench(bench) {
  kmx.bench = bench;
  const off = !!bench.why;
  document.querySelectorAll("#bench button, #bench input").forEach((el) => { el.disabled = off; });
  $("bench-why").textContent = off ? bench.why : "emulated servos with a bench: ID " + bench.servos.join(", ");
  $("bench-why").className = "msg " + (off ? "error" : "ok");
}

// One bench change on the chosen servo, then the protection watched.
async function benchPost(body) {
  const r = await api("/api/servo/" + currentId() + "/bench", body);
  if (r.ok) say("bench-msg", "ID " + currentId() + ": " + r.applied.join(", "), true);
  else say("bench-msg", r.error, false);
  if (r.ok && !kmx.benchWatch) { kmx.benchWatch = true; watchProtection(); }
}

// While the bench is in use: the chosen servo's status and protection, twice a second.
async function watchProtection() {
  while (kmx.benchWatch) {
    const r = await api("/api/servo/" + currentId() + "/protection");
    if (r.ok) {
      $("bench-status").textContent = r.status + " (0x" + r.status_byte.toString(16).padStart(2, "0") + ")";
      $("bench-protecting").textContent = r.protecting;
      $("bench-temperature").textContent = r.temperature;
      $("bench-voltage").textContent = r.voltage;
    } else $("bench-status").textContent = r.error;
    await new Promise((res) => setTimeout(res, 500));
  }
}

async function connect(ev) {
  ev.preventDefault();
  kmx.benchWatch = false; // the servo watched was on the bus before
  if (kmx.live) toggleLive(); // so were the servos plotted: their sampling stops
  const r = await api("/api/connect", { bus: $("bus").value.trim() });
  if (r.ok) showState(r); else $("busline").textContent = "not connected: " + r.error;
}

// Polls /api/job until it is done; onStep(job) each time.
async function follow(onStep) {
  for (;;) {
    const r = await api("/api/job");
    if (r.ok && r.job) {
      onStep(r.job);
      if (r.job.done) return r.job;
    }
    await new Promise((res) => setTimeout(res, 100));
  }
}

async function scan() {
  $("scan-btn").disabled = true;
  $("scan-progress").value = 0;
  const start = await api("/api/scan", { all_bauds: $("all-bauds").checked });
  if (!start.ok) { $("busline").textContent = start.error; $("scan-btn").disabled = false; return; }
  const job = await follow((j) => { $("scan-progress").value = j.progress; });
  $("scan-btn").disabled = false;
  const body = $("servos").tBodies[0];
  body.innerHTML = "";
  if (job.error) { $("busline").textContent = job.error; return; }
  kmx.servos = job.result.map((s) => s.id);
  for (const s of job.result) {
    const tr = body.insertRow();
    for (const v of [s.id, s.baud, s.model, s.firmware, s.status]) tr.insertCell().textContent = v;
  }
  const sel = $("servo-id");
  sel.innerHTML = "";
  for (const id of kmx.servos) sel.add(new Option("ID " + id, id));
  $("busline").textContent = kmx.servos.length + " servos found on " + $("bus").value;
  makeCharts();
}

async function servoPost(what, body, msgId) {
  const r = await api("/api/servo/" + currentId() + "/" + what, body);
  if (r.ok) say(msgId, r.name + " = " + r.value, true); else say(msgId, r.error, false);
  return r;
}

function makeCharts() {
  if (typeof Chart === "undefined") return; // libjs-chart.js missing: the numbers still show in the table
  for (const [q, unit] of QUANTITIES) {
    if (kmx.charts[q]) kmx.charts[q].destroy();
    kmx.charts[q] = new Chart($("chart-" + q), {
      type: "line",
      data: { datasets: kmx.servos.map((id, n) => ({ label: "ID " + id, data: [], borderColor: COLORS[n % 8],
                                                     pointRadius: 0, borderWidth: 1.5 })) },
      options: { animation: false, parsing: false, normalized: true, maintainAspectRatio: false,
                 scales: { x: { type: "linear", title: { display: true, text: "s" } },
                           y: { title: { display: true, text: q + " (" + unit + ")" } } } },
    });
  }
}

// Draws the charts on screen at the next animation frame, once however many
// samples came; one scrolled out of view is drawn when it comes back
// (watchCharts), so a phone or a loaded machine spends no CPU on hidden ones.
function redraw() {
  if (kmx.drawPending) return;
  kmx.drawPending = true;
  requestAnimationFrame(() => {
    kmx.drawPending = false;
    for (const [q] of QUANTITIES) if (kmx.charts[q] && kmx.onScreen.has(q)) kmx.charts[q].update("none");
  });
}

// Keeps kmx.onScreen: the quantities whose chart is in view (all of them without IntersectionObserver).
function watchCharts() {
  kmx.onScreen = new Set(QUANTITIES.map(([q]) => q));
  if (typeof IntersectionObserver === "undefined") return;
  const seen = new IntersectionObserver((entries) => {
    for (const e of entries) {
      const q = e.target.id.slice("chart-".length);
      if (!e.isIntersecting) { kmx.onScreen.delete(q); continue; }
      kmx.onScreen.add(q);
      if (kmx.charts[q]) kmx.charts[q].update("none");
    }
  });
  for (const [q] of QUANTITIES) seen.observe($("chart-" + q));
}

// The live loop: the server samples every servo at 20 Hz (0x82 reads); the
// page takes the new samples five times a second and draws them.
async function liveLoop() {
  let since = 0;
  await api("/api/live/start", { ids: kmx.servos, period_ms: 50 });
  while (kmx.live) {
    const r = await api("/api/live/data?since=" + since);
    if (!r.ok) $("live-rate").textContent = r.error;
    const fresh = (r.samples || []).length > 0;
    for (const sample of r.samples || []) {
      since = sample.seq;
      kmx.samples++;
      for (const [q] of QUANTITIES) {
        const chart = kmx.charts[q];
        if (!chart) continue;
        kmx.servos.forEach((id, n) => {
          const s = sample.servos[id];
          const data = chart.data.datasets[n].data;
          if (s && s[q] !== null && s[q] !== undefined) data.push({ x: sample.t, y: s[q] });
          if (data.length > KEEP) data.shift();
        });
      }
    }
    if (r.rate) {
      kmx.rate = r.rate;
      kmx.took = r.took;
      let text = r.rate.toFixed(1) + " samples/s of " + kmx.servos.length + " servos (0x82)";
      if (r.rate < 0.9 * r.asked) text += "; " + r.asked.toFixed(0) + " asked, one sample takes " +
        (1000 * r.took).toFixed(0) + " ms here (a busy bus or computer)";
      $("live-rate").textContent = text;
    }
    if (fresh) redraw();
    await new Promise((res) => setTimeout(res, 200));
  }
  await api("/api/live/stop", {});
}

function toggleLive() {
  kmx.live = !kmx.live;
  $("live-btn").textContent = kmx.live ? "Stop plots" : "Start plots";
  $("live-btn").setAttribute("aria-pressed", String(kmx.live));
  if (kmx.live) { if (!kmx.charts.position) makeCharts(); liveLoop(); }
}

// The range text of a field: "0..360 °/s" (product bounds say "product").
function rangeText(f) {
  const show = (b) => (typeof b === "number" ? +(b * (f.unit ? f.scale : 1)).toFixed(3) : b);
  if (f.min === null && f.max === null) return "";
  return show(f.min) + ".." + show(f.max) + (f.unit ? " " + f.unit : "");
}

function editCell(reg, td) {
  if (!reg.access.includes("W")) { td.textContent = "read-only"; return; }
  const form = document.createElement("form");
  let input;
  if (reg.enum) {
    input = document.createElement("select");
    for (const [code, words] of Object.entries(reg.enum)) input.add(new Option(code + " " + words, code));
    if (reg.number !== null) input.value = String(reg.number);
  } else {
    input = document.createElement("input");
    input.placeholder = reg.fields.map((f) => f.unit || "value").join(", ");
  }
  input.setAttribute("aria-label", "new " + reg.name);
  input.name = "value";
  input.dataset.reg = reg.name;
  const button = document.createElement("button");
  button.textContent = "Set";
  button.type = "submit";
  const out = document.createElement("span");
  out.className = "result";
  out.setAttribute("role", "status");
  form.append(input, button, out);
  form.addEventListener("submit", async (ev) => {
    ev.preventDefault();
    const r = await api("/api/servo/" + currentId() + "/set", { name: reg.name, value: input.value });
    out.textContent = r.ok ? " → " + r.value : " " + r.error;
    out.className = r.ok ? "result" : "result error";
    if (r.ok) td.parentElement.cells[2].textContent = r.value;
  });
  td.append(form);
}

async function readTable() {
  say("table-msg", "reading…", true);
  const r = await api("/api/servo/" + currentId() + "/registers");
  if (!r.ok) { say("table-msg", r.error, false); return; }
  say("table-msg", "ID " + currentId() + ": " + r.registers.length + " registers", true);
  const body = $("regs").tBodies[0];
  body.innerHTML = "";
  for (const reg of r.registers) {
    const tr = body.insertRow();
    tr.dataset.reg = reg.name;
    tr.insertCell().textContent = reg.address;
    const name = tr.insertCell();
    name.textContent = reg.name;
    name.title = reg.title + ": " + reg.description;
    let value = reg.value === null ? "(write-only)" : reg.value;
    if (reg.enum && reg.number !== null && reg.enum[reg.number]) value += " (" + reg.enum[reg.number] + ")";
    tr.insertCell().textContent = value;
    tr.insertCell().textContent = reg.fields.map(rangeText).filter((t) => t).join("; ");
    editCell(reg, tr.insertCell());
  }
}

async function readFaults() {
  const r = await api("/api/servo/" + currentId() + "/faults");
  if (!r.ok) { $("faults-summary").textContent = r.error; return; }
  $("faults-summary").textContent = r.events + " events recorded, " + r.held + " held; last reset: " + r.reset +
    "; user data: " + r.userdata;
  const t = $("fault-rows");
  t.tHead.innerHTML = "";
  t.tBodies[0].innerHTML = "";
  if (!r.entries.length) return;
  const head = t.tHead.insertRow();
  for (const k of Object.keys(r.entries[0])) head.insertCell().textContent = k;
  for (const e of r.entries) {
    const tr = t.tBodies[0].insertRow();
    for (const v of Object.values(e)) tr.insertCell().textContent = v;
  }
}

async function setup(what, body) {
  const r = await api("/api/servo/" + currentId() + "/" + what, body);
  $("setup-out").textContent = r.ok ? r.lines.join("\n") : r.error;
  if (r.ok && what === "set-id") { // the bench names its servos by the ID they answer at now
    const st = await api("/api/state");
    if (st.ok && st.bench) showBench(st.bench);
  }
}

async function rescue() {
  const start = await api("/api/rescue", {});
  if (!start.ok) { $("setup-out").textContent = start.error; return; }
  const job = await follow((j) => { $("setup-out").textContent = j.lines.join("\n"); });
  if (job.error) $("setup-out").textContent += "\n" + job.error;
}

async function update(ev) {
  ev.preventDefault();
  const form = new FormData($("update-form"));
  $("update-end").textContent = "";
  let r;
  try {
    r = await (await fetch("/api/update", { method: "POST", body: form })).json();
  } catch (e) { r = { ok: false, error: e.message }; }
  if (!r.ok) { say("update-end", r.error, false); return; }
  const job = await follow((j) => {
    $("update-progress").value = j.progress;
    $("update-log").textContent = j.lines.join("\n");
    const body = $("update-servos").tBodies[0];
    body.innerHTML = "";
    for (const [id, s] of Object.entries(j.servos)) {
      const tr = body.insertRow();
      tr.insertCell().textContent = id === "254" ? "(rescue)" : id;
      tr.insertCell().textContent = s.state;
      tr.insertCell().textContent = s.blocks ? s.received + " / " + s.blocks : "";
    }
  });
  if (job.error) say("update-end", "stopped: " + job.error, false);
  else say("update-end", job.result.ok ? "done: every servo runs the new image" : "done, but not every servo took the image", job.result.ok);
}

function wire() {
  watchCharts();
  $("connect-form").addEventListener("submit", connect);
  $("scan-btn").addEventListener("click", scan);
  document.querySelectorAll("[data-torque]").forEach((b) =>
    b.addEventListener("click", () => servoPost("torque", { state: b.dataset.torque }, "servo-msg")));
  $("move-slider").addEventListener("input", () => { $("move-value").textContent = (+$("move-slider").value).toFixed(1); });
  $("move-btn").addEventListener("click", () =>
    servoPost("move", { angle: +$("move-slider").value, time_ms: +$("move-time").value }, "servo-msg"));
  document.querySelectorAll("[data-jog]").forEach((b) => b.addEventListener("click", async () => {
    const slider = $("move-slider");
    slider.value = +slider.value + +b.dataset.jog;
    $("move-value").textContent = (+slider.value).toFixed(1);
    await servoPost("jog", { angle: +slider.value }, "servo-msg");
  }));
  $("live-btn").addEventListener("click", toggleLive);
  $("read-table").addEventListener("click", readTable);
  $("faults-btn").addEventListener("click", readFaults);
  $("set-id-btn").addEventListener("click", () => setup("set-id", { new: $("new-id").value }));
  $("set-baud-btn").addEventListener("click", () => setup("set-baud", { baud: $("new-baud").value }));
  $("rescue-btn").addEventListener("click", rescue);
  $("update-form").addEventListener("submit", update);
  document.querySelectorAll("[data-bench]").forEach((b) =>
    b.addEventListener("click", () => benchPost({ preset: b.dataset.bench })));
  $("bench-load-btn").addEventListener("click", () =>
    benchPost({ key: "load_mnm", value: Math.round(+$("bench-load").value * 1000) }));
  api("/api/state").then((st) => { if (st.ok) showState(st); });
}

wire();
