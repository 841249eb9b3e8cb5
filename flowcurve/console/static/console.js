// flowcurve console page: set-up form, live plots (server-sent events), post-test form, records.
"use strict";

const $ = (sel) => document.querySelector(sel);
const RUNNING = new Set(["starting", "heating", "soaking", "tare", "waiting", "recording", "stopping"]);
const ENDED = new Set(["complete", "aborted", "failed"]);  // each its own word and colour
const STALE_S = 2;  // readings older than this (wall seconds) are marked stale
// result figures: key → [words, unit, factor] (the page never shows a raw key)
const FIGURES = {
  E_MPa: ["E", "GPa", 1e-3], Rp02_MPa: ["Rp0.2", "MPa", 1], Rm_MPa: ["Rm", "MPa", 1],
  A_pct: ["elongation after fracture A", "%", 1], Z_pct: ["reduction of area Z", "%", 1],
  fracture_true_strain: ["true strain at fracture", "", 1], friction_mu: ["friction coefficient μ", "", 1],
  final_true_strain: ["final true strain", "", 1], max_force_N: ["maximum force", "kN", 1e-3],
  "JC A_MPa": ["Johnson–Cook A", "MPa", 1], "JC B_MPa": ["Johnson–Cook B", "MPa", 1], "JC n": ["Johnson–Cook n", "", 1],
  "JC fit_error_pct": ["Johnson–Cook fit error (max)", "%", 1],
};
function figureLabel(k) { const f = FIGURES[k]; return f ? f[0] + (f[1] ? `, ${f[1]}` : "") : k.replace(/_/g, " "); }
function figureValue(k, v) { const f = FIGURES[k]; return typeof v === "number" && f ? v * f[2] : v; }
const stats = { fdPoints: 0, ttPoints: 0, draws: 0, fdDraws: 0, events: 0, latencies_ms: [] };  // read by the browser tests and the bench
window.fcStats = stats;
let info = null;
let currentTest = null;
let lastState = "idle";
let postShownFor = null;
let connected = false;
let requestNote = "";  // what Stop or Abort asked for, shown until the test ends
let lastStatus = { state: "idle" };
let statusAt = 0;  // performance.now() when lastStatus arrived

function num(v) {
  if (typeof v !== "number") return String(v ?? "");
  return Math.abs(v) >= 1000 ? v.toFixed(0) : Number(v.toPrecision(4)).toString();
}
function fmt(v, digits) { return v === null || v === undefined || !isFinite(v) ? "—" : Number(v).toFixed(digits); }
function esc(s) { return String(s ?? "").replace(/[&<>"']/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;", "'": "&#39;" }[c])); }

async function api(path, body) {
  const opts = body === undefined ? {} : { method: "POST", headers: { "Content-Type": "application/json" }, body: JSON.stringify(body) };
  let resp;
  try { resp = await fetch(path, opts); } catch (e) { return { ok: false, status: 0, data: { error: "the console does not answer (connection lost)" } }; }
  let data = {};
  try { data = await resp.json(); } catch (e) { data = { error: `${resp.status} ${resp.statusText}` }; }
  if (resp.status === 401 && data.token_required) { askToken(); }
  return { ok: resp.ok, status: resp.status, data };
}

// -- plots -----------------------------------------------------------------------------------
// axes from zero (force, displacement, time); temperature spans at least 10 °C so noise stays noise
const fromZero = (u, min, max) => (min === null || max === null ? [0, 1] : uPlot.rangeNum(Math.min(0, min), Math.max(max, min + 1e-6), 0.05, true));
const atLeast10C = (u, min, max) => {
  if (min === null || max === null) return [0, 100];
  const mid = (min + max) / 2, half = Math.max((max - min) / 2, 5);
  return uPlot.rangeNum(mid - half, mid + half, 0.05, true);
};

function makePlot(el, xLabel, yLabel, color, yRange) {
  const width = () => Math.max(280, el.clientWidth);
  const plot = new uPlot({
    width: width(), height: 240,
    scales: { x: { time: false, range: fromZero }, y: { range: yRange } },
    legend: { show: false },
    cursor: { drag: { x: false, y: false } },
    axes: [{ label: xLabel, size: 40 }, { label: yLabel, size: 60 }],
    series: [{ label: xLabel }, { label: yLabel, stroke: color, width: 1.5, points: { show: false } }],
    hooks: { draw: [() => onDraw(el.id)] },
  }, [[], []], el);
  new ResizeObserver(() => plot.setSize({ width: width(), height: 240 })).observe(el);
  return plot;
}

const plots = {};
const data = { fd: { x: [], y: [] }, tt: { x: [], y: [] } };
let pendingDraw = false;
let pendingSampleEpoch = null;

function onDraw(id) {
  stats.draws += 1;
  if (id === "plot-fd") stats.fdDraws += 1;
  if (id === "plot-fd" && pendingSampleEpoch !== null) {
    stats.latencies_ms.push(Date.now() - pendingSampleEpoch * 1000);
    if (stats.latencies_ms.length > 5000) stats.latencies_ms.shift();
    pendingSampleEpoch = null;
  }
}

function addPoints(p) {
  for (const name of ["fd", "tt"]) {
    const part = p[name];
    if (!part) continue;
    if (part.reset) { data[name].x = []; data[name].y = []; }
    data[name].x.push(...part.x);
    data[name].y.push(...part.y);
  }
  if (p.last_sample_epoch_s) pendingSampleEpoch = p.last_sample_epoch_s;
  if (!pendingDraw) { pendingDraw = true; requestAnimationFrame(drawPlots); }
}

// the newest reading (status, 20/s) drawn after the recorded rows, which the sampler releases only
// once every channel has caught up with them (the furnace is read 4 times a second on a real rig)
let tail = null;

function showTail(s) {
  const live = s.state === "recording" && s.crosshead_mm !== null && s.force_N !== null && s.crosshead_mm !== undefined;
  tail = live ? [s.crosshead_mm, s.force_N] : null;
  if (!pendingDraw) { pendingDraw = true; requestAnimationFrame(drawPlots); }
}

function drawPlots() {
  pendingDraw = false;
  const fx = tail ? data.fd.x.concat([tail[0]]) : data.fd.x;
  const fy = tail ? data.fd.y.concat([tail[1]]) : data.fd.y;
  plots.fd.setData([fx, fy.map((f) => f / 1000)]);
  plots.tt.setData([data.tt.x, data.tt.y]);
  stats.fdPoints = data.fd.x.length;
  stats.ttPoints = data.tt.x.length;
  $("#fd-count").textContent = stats.fdPoints;
  $("#tt-count").textContent = stats.ttPoints;
}

function clearPlots() {
  for (const name of ["fd", "tt"]) { data[name].x = []; data[name].y = []; }
  drawPlots();
}

// -- live state ------------------------------------------------------------------------------
function showStatus(s) {
  connected = true;
  lastStatus = s;
  statusAt = performance.now();
  const state = s.state || "idle";
  const badge = $("#state");
  badge.textContent = state;
  badge.className = `badge state-${state}`;
  const heater = $("#heater");
  heater.textContent = s.heater || "off";
  heater.className = `badge heater-${s.heater || "off"}`;
  showScale(s.time_scale);
  showProgress(s);
  $("#r-time").textContent = fmt(s.time_s, 1);
  $("#r-force").textContent = s.force_N === null || s.force_N === undefined ? "—" : fmt(s.force_N / 1000, 3);
  $("#r-cross").textContent = fmt(s.crosshead_mm, 3);
  $("#r-temp").textContent = fmt(s.temperature_C, 1);
  $("#r-samples").textContent = s.samples ?? 0;
  const msg = $("#message");
  if (!RUNNING.has(state)) requestNote = "";
  msg.textContent = s.message || requestNote || (s.messages && s.messages.length ? s.messages[s.messages.length - 1] : "");
  msg.className = ENDED.has(state) ? `message ${state}` : "message";
  setControls(RUNNING.has(state));
  if (lastState !== state && ENDED.has(state)) loadRecords();
  lastState = state;
  showStale();
}

function setControls(running) {
  $("#btn-start").disabled = running || !connected;
  $("#btn-stop").disabled = !running || !connected;
  $("#btn-abort").disabled = !running || !connected;
  for (const el of document.querySelectorAll("#setup input, #setup select")) el.disabled = running || !connected || (el.id === "f-fault" && !(info && info.virtual));
}

// the readings' age: as the server said when it sent them, plus the time since
function readingsAge() { return (lastStatus.readings_age_s ?? 0) + (performance.now() - statusAt) / 1000; }

function showStale() {
  const el = $("#stale");
  const hasReadings = !["idle", "starting"].includes(lastStatus.state) && lastStatus.time_s !== undefined;
  const age = readingsAge();
  const stale = hasReadings && (!connected || age > STALE_S);
  document.querySelector(".readings").classList.toggle("stale", stale);
  if (!stale) { el.textContent = ""; return; }
  const heated = currentTest && currentTest.setup && String(currentTest.setup.temperature || "").trim() !== "";
  const hot = typeof lastStatus.temperature_C === "number" && (lastStatus.temperature_C > 50 || heated);
  const why = !connected ? "not updated: no connection to the console" :
    ENDED.has(lastStatus.state) ? "as of the end of the test: nothing reads the rig now" : "not updated";
  el.textContent = `readings stale — ${why} (read ${fmt(age, 0)} s ago)` +
    (hot ? `; the furnace was heated (last ${fmt(lastStatus.temperature_C, 0)} °C) and may still be hot` : "");
}

function showScale(scale) {
  const el = $("#time-scale");
  const x = scale ?? (info && info.time_scale);
  el.textContent = !x || x === 1 ? "real time" : `time ×${num(x)}: 1 s here is ${num(x)} s of test time`;
  el.className = !x || x === 1 ? "dim" : "scale";
}

function showProgress(s) {
  const box = $("#progress-box");
  const heating = s.state === "heating" && typeof s.progress === "number";
  box.hidden = !heating;
  if (!heating) return;
  $("#heat-progress").value = s.progress;
  const target = currentTest && currentTest.setup ? currentTest.setup.temperature : "";
  $("#heat-progress-text").textContent = `heating${target ? ` to ${target} °C` : ""}: ${fmt(100 * s.progress, 0)} % of the way` +
    (typeof s.temperature_C === "number" ? ` (now ${fmt(s.temperature_C, 1)} °C)` : "");
}

function connectionLost(message) {
  connected = false;
  const badge = $("#state");
  badge.textContent = "connection lost";
  badge.className = "badge state-lost";
  $("#heater").textContent = "unknown";
  $("#heater").className = "badge heater-none";
  $("#message").textContent = message || "Connection to the console lost: Start, Stop and Abort are off until it is back (retrying). " +
    "If the console was stopped, start it again (flowcurve console) and reload this page; the machine's own emergency stop works without it.";
  $("#message").className = "message lost";
  setControls(RUNNING.has(lastStatus.state));
  showStale();
}

function showTest(t) {
  const isNew = !currentTest || !t || currentTest.test_id !== t.test_id;
  currentTest = t;
  if (!t) { $("#record-name").textContent = ""; $("#post-panel").hidden = true; return; }  // no test (one refused before it began is forgotten)
  if (isNew && t.running && t.setup) {  // another page started it: show what it was set up with
    const form = $("#setup");
    for (const [name, value] of Object.entries(t.setup)) if (form.elements[name]) form.elements[name].value = value;
    setTestType();
  }
  $("#record-name").textContent = t.record ? `— ${t.record}` : "";
  const panel = $("#post-panel");
  if (t.running || t.status === null) { panel.hidden = true; return; }
  panel.hidden = false;
  const link = t.record_url ? ` <a href="${esc(t.record_url)}" target="_blank">${esc(t.record)}</a>` : "";
  $("#outcome").innerHTML = `Record${link}: ${esc(t.status ?? "not written")}${t.reason ? ` — ${esc(t.reason)}` : ""}` +
    (t.samples !== null && t.samples !== undefined ? ` (${t.samples} samples, ${fmt(t.duration_s, 1)} s test time, max force ${fmt((t.max_force_N || 0) / 1000, 2)} kN)` : "") +
    (t.error ? `<br><span class="error">fault: ${esc(t.error)}</span>` : "");
  if (postShownFor !== t.test_id) {
    postShownFor = t.test_id;
    const keys = (info && info.post[t.test]) || [];
    $("#post-fields").innerHTML = keys.map((k) => `<label>${esc((t.post_prompts || info.prompts)[k] || k)}<input name="${esc(k)}" id="p-${esc(k.replace("post.", ""))}" inputmode="decimal" value="${t.post && t.post[k] !== undefined ? esc(t.post[k]) : ""}"><span class="field-error" data-for="${esc(k)}"></span></label>`).join("");
  }
  $("#post").hidden = t.status !== "complete";
  showResult(t.result);
}

function showResult(r) {
  const el = $("#result");
  if (!r) { el.innerHTML = ""; return; }
  if (r.error) { el.innerHTML = `<p class="error" id="result-error">identification: ${esc(r.error)}</p>`; return; }
  const figures = Object.entries(r.figures || {}).map(([k, v]) => `<div data-key="${esc(k)}"><span class="dim">${esc(figureLabel(k))}</span> <b>${esc(num(figureValue(k, v)))}</b></div>`).join("");
  const files = (r.files || []).map((f) => `<a href="${esc(f.url)}" target="_blank">${esc(f.name)}</a>`).join(" · ");
  const warnings = (r.warnings || []).map((w) => `<li>${esc(w)}</li>`).join("");
  const imgs = (r.plots || []).map((u) => `<a href="${esc(u)}" target="_blank"><img src="${esc(u)}?v=${Date.now()}" alt="${esc(u.split("/").pop())}"></a>`).join("");
  el.innerHTML = `<h3 id="result-title">Identified (${esc(r.hardening_law || "")})</h3><div class="figures" id="result-figures">${figures}</div>` +
    (warnings ? `<ul class="hint">${warnings}</ul>` : "") + `<p>files: ${files}</p><div class="result-plots">${imgs}</div>`;
}

let source = null;

function connect() {
  if (source) source.close();
  const es = new EventSource("/api/events");
  source = es;
  es.addEventListener("status", (e) => { stats.events += 1; const s = JSON.parse(e.data); showStatus(s); showTail(s); });
  es.addEventListener("test", (e) => {
    const t = JSON.parse(e.data);
    if (!currentTest || !t || currentTest.test_id !== t.test_id) clearPlots();
    showTest(t);
  });
  es.addEventListener("points", (e) => { stats.events += 1; addPoints(JSON.parse(e.data)); });
  es.addEventListener("closing", (e) => {  // the console is shutting down: its last word, then try again later
    connectionLost(`${JSON.parse(e.data).message}. Start, Stop and Abort are off until it is back.`);
    es.close();
    setTimeout(connect, 3000);
  });
  es.onerror = () => {
    if (connected) connectionLost();
    if (es.readyState === EventSource.CLOSED) setTimeout(connect, 3000);
  };
}

// -- forms -----------------------------------------------------------------------------------
function formValues(form) {
  const out = {};
  for (const el of form.elements) if (el.name) out[el.name] = el.value;
  return out;
}

function showFieldErrors(form, fields) {
  for (const p of form.querySelectorAll(".field-error")) p.textContent = "";
  for (const el of form.querySelectorAll(".invalid")) el.classList.remove("invalid");
  for (const [name, msg] of Object.entries(fields || {})) {
    const p = form.querySelector(`.field-error[data-for="${CSS.escape(name)}"]`) || form.querySelector('.field-error[data-for="form"]');
    if (p) p.textContent = msg;
    const input = form.elements[name];
    if (input && input.classList) input.classList.add("invalid");
  }
}

async function startTest(ev) {
  ev.preventDefault();
  if (!connected) return;  // the rig's state and heater are not known yet (connecting, or the connection lost)
  const form = $("#setup");
  showFieldErrors(form, {});
  const { ok, status, data } = await api("/api/start", formValues(form));
  if (!ok) {
    showFieldErrors(form, data.fields || { form: data.error });
    if (status === 409) $("#message").textContent = data.error;
    return;
  }
  postShownFor = null;
}

async function submitPost(ev) {
  ev.preventDefault();
  const form = $("#post");
  showFieldErrors(form, {});
  $("#btn-post").disabled = true;
  $("#result").innerHTML = `<p class="hint">identifying…</p>`;
  try {
    const { ok, data } = await api("/api/post", formValues(form));
    if (!ok) { showFieldErrors(form, data.fields || { form: data.error }); $("#result").innerHTML = ""; return; }
    showTest(data.test);
    loadRecords();
  } finally { $("#btn-post").disabled = false; }
}

async function loadRecords() {
  const { ok, data } = await api("/api/records");
  if (!ok) return;
  const rows = data.records.map((r) => {
    const res = r.result;
    let resText = "—";
    if (res && res.error) resText = `<span class="error">${esc(res.error)}</span>`;
    else if (res) resText = Object.entries(res.figures).filter(([k]) => /JC [ABn]|friction|Rm|E_MPa/.test(k)).map(([k, v]) => `${esc(figureLabel(k))} ${esc(num(figureValue(k, v)))}`).join("; ") + ` <a href="${esc(res.folder)}/result.json" target="_blank">result</a>`;
    return `<tr><td><input type="checkbox" name="rec" value="${esc(r.name)}" aria-label="select ${esc(r.name)}"></td>` +
      `<td><a href="${esc(r.url)}" target="_blank">${esc(r.name)}</a></td><td>${esc(r.test)}</td><td>${esc(r.material)}</td>` +
      `<td>${esc(r.specimen_id)}</td><td>${esc(r.status)}${r.error ? ` <span class="error">${esc(r.error)}</span>` : ""}</td><td>${resText}</td></tr>`;
  });
  $("#records tbody").innerHTML = rows.join("") || `<tr><td colspan="7" class="dim">no records yet</td></tr>`;
}

async function runFit(ev) {
  ev.preventDefault();
  const form = $("#fit");
  const names = [...document.querySelectorAll('#records input[name="rec"]:checked')].map((c) => c.value);
  showFieldErrors(form, {});
  $("#fit-result").innerHTML = `<p class="hint">fitting…</p>`;
  const { ok, data } = await api("/api/fit", { records: names, ...formValues(form) });
  if (!ok) { showFieldErrors(form, { ...(data.fields || {}), fit: data.error }); $("#fit-result").innerHTML = ""; return; }
  const imgs = data.plots.map((u) => `<img src="${esc(u)}" alt="">`).join("");
  $("#fit-result").innerHTML = `<p><a id="card-link" href="${esc(data.card)}?download" download="${esc(data.card_name)}">download ${esc(data.card_name)}</a> · <a href="${esc(data.fit)}" target="_blank">fit.json</a></p><pre>${esc(data.summary)}</pre><div class="result-plots">${imgs}</div>`;
}

// Stop and Abort say what they asked for, and when the console did not get it
async function request(what, asked) {
  const msg = $("#message");
  msg.textContent = requestNote = asked;
  msg.className = "message";
  const { ok, data } = await api(`/api/${what}`, {});
  if (!ok) { msg.textContent = requestNote = `${what} NOT delivered: ${data.error} — use the machine's own stop`; msg.className = "message fault"; }
  else if (!data.stopping && !data.aborting) { msg.textContent = `${what}: no test is running`; }
}

function setTestType() {
  document.body.classList.toggle("test-tension", $("#f-test").value === "tension");
  document.body.classList.toggle("test-compression", $("#f-test").value === "compression");
}

// -- token -----------------------------------------------------------------------------------
function askToken() {
  const dlg = $("#token-dialog");
  if (!dlg.open) dlg.showModal();
}

async function sendToken(ev) {
  ev.preventDefault();
  const { ok, data } = await api("/api/login", { token: $("#token").value });
  if (!ok) { $("#token-error").textContent = data.error; return; }
  $("#token-dialog").close();
  boot();
}

function fillChoices(selector, choices) {
  $(selector).replaceChildren(...choices.map(([value, shown]) => {
    const option = document.createElement("option");
    option.value = value;
    option.textContent = shown;
    return option;
  }));
}

async function boot() {
  const res = await api("/api/info");
  if (!res.ok) return;
  info = res.data;
  if (info.token_required) {
    const probe = await api("/api/status");
    if (!probe.ok) return;
  }
  if (info.card_formats) {  // the card registry's formats (reports/card_formats.py): a new one needs no edit here
    fillChoices("#fit-format", info.card_formats.map(([name, shown]) => [name, `${name} (${shown})`]));
  }
  // the law, method, unit-system and LS-DYNA-material registries, the default first
  [["#fit-law", info.laws], ["#fit-method", info.fit_methods], ["#fit-units", info.unit_systems], ["#fit-lsdyna", info.lsdyna_materials]]
    .forEach(([sel, choices]) => { if (choices) fillChoices(sel, choices); });
  $("#rig").textContent = `— ${info.rig}`;
  showScale(info.time_scale);
  $("#out").textContent = info.out;
  $("#setup-hint").textContent = info.virtual ? "Virtual rig: empty geometry and speed take the virtual specimen's and run's defaults." : "";
  $("#fault-row").hidden = !info.virtual;  // fault drills: the virtual rig only
  $("#fault-hint").textContent = info.virtual ? info.fault_help || "" : "";
  connect();
  loadRecords();
}

window.addEventListener("DOMContentLoaded", () => {
  plots.fd = makePlot($("#plot-fd"), "crosshead displacement, mm", "force, kN", "#1f5fbf", fromZero);
  plots.tt = makePlot($("#plot-tt"), "test time, s", "temperature, °C", "#b3261e", atLeast10C);
  $("#setup").addEventListener("submit", startTest);
  $("#post").addEventListener("submit", submitPost);
  $("#fit").addEventListener("submit", runFit);
  $("#f-test").addEventListener("change", setTestType);
  $("#btn-stop").addEventListener("click", () => request("stop", "Stop asked: recording ends at the next reading and the record is kept, complete."));
  $("#btn-abort").addEventListener("click", () => { if (confirm("Abort the test? The record is kept and marked aborted.")) request("abort", "Abort asked: the heater goes off and the test ends at once; the record is kept, marked aborted."); });
  setInterval(showStale, 500);
  $("#btn-refresh").addEventListener("click", loadRecords);
  $("#token-form").addEventListener("submit", sendToken);
  setTestType();
  boot();
});
