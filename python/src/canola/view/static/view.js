// SPDX-License-Identifier: Apache-2.0
// canola view: the page. Updates come over a WebSocket (/ws) a few times a second; the
// server sends a bounded amount each time and says what it left out. Every string from the
// bus or an EDS is written as text (textContent, Option), never as HTML.
"use strict";

const MAX_EVENTS = 2000;     // entries kept in the event list
const MAX_FRAMES = 400;      // rows kept in the raw frame list
const KEEP_S = 300;          // seconds of signal history kept in the page
const KINDS = ["bootup", "nmt", "state", "emcy", "heartbeat", "sdo", "view", "bus"];
const COLORS = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#17becf"];

const $ = (id) => document.getElementById(id);
const token = new URLSearchParams(location.hash.slice(1)).get("token") || "";

const state = {
  nodes: [], signals: new Map(), series: new Map(), charts: new Map(),
  selected: new Set(), autoSelected: 0, paused: false, od: null, odNode: null, now: 0,
  left: {events: 0, frames: 0, points: 0},
};
window.canolaView = state;  // for the browser tests: what is plotted

function el(tag, text, cls) {
  const e = document.createElement(tag);
  if (text !== undefined && text !== null) e.textContent = String(text);
  if (cls) e.className = cls;
  return e;
}

function hex(n, digits) { return "0x" + n.toString(16).toUpperCase().padStart(digits, "0"); }

function clock(t) {
  const d = new Date(t * 1000);
  const two = (n) => String(n).padStart(2, "0");
  return `${two(d.getHours())}:${two(d.getMinutes())}:${two(d.getSeconds())}.` +
    String(d.getMilliseconds()).padStart(3, "0");
}

// ---- the connection

function connect() {
  const ws = new WebSocket((location.protocol === "https:" ? "wss://" : "ws://") +
                           location.host + "/ws");
  ws.onopen = () => { $("link").textContent = "live"; $("link").className = "pill ok"; };
  ws.onclose = () => {
    $("link").textContent = "disconnected: retrying";
    $("link").className = "pill bad";
    setTimeout(connect, 2000);
  };
  ws.onmessage = (msg) => {
    const data = JSON.parse(msg.data);
    if (data.type === "hello") hello(data);
    else if (data.type === "update") update(data);
  };
}

function hello(h) {
  const known = h.dictionary_nodes.map((n) => ({node: n}));
  for (const id of ["sdo-node", "nmt-node"]) nodeChoices($(id), known);
  const w = $("writes");
  if (!h.allow_write) {
    w.textContent = "writes off (--allow-write)";
    w.className = "pill";
  } else if (h.local || token) {
    w.textContent = "writes on";
    w.className = "pill warn";
  } else {
    w.textContent = "writes need the token";
    w.className = "pill";
  }
}

function update(u) {
  state.now = u.now;
  $("bus-state").textContent = u.bus_state;
  const t = u.traffic;
  $("bus-load").textContent = `${t.load_pct.toFixed(1)} %`;
  $("bus-fps").textContent = t.fps_all.toFixed(0);
  $("bus-total").textContent = t.total;
  $("pages").textContent = u.pages > 1 ? `${u.pages} pages open` : "";
  $("load-note").textContent = `load: the frames' bits over ${t.bitrate} bit/s, stuff bits ` +
    "left out (a lower bound)";
  nodes(u.nodes);
  fps(t.fps);
  if (u.signals) signalList(u.signals);
  events(u.events);
  frames(u.frames);
  points(u.points);
  leftOut(u.left_out);
}

// ---- nodes

function identity(id) {
  const parts = [];
  if (id.vendor !== undefined) parts.push(`vendor ${hex(id.vendor, 8)}`);
  if (id.product !== undefined) parts.push(`product ${hex(id.product, 8)}`);
  if (id.revision !== undefined) parts.push(`rev ${hex(id.revision, 8)}`);
  if (id.serial !== undefined) parts.push(`serial ${hex(id.serial, 8)}`);
  return parts.join(", ") || "-";
}

function nodes(rows) {
  state.nodes = rows;
  $("no-nodes").hidden = rows.length > 0;
  const body = $("nodes").tBodies[0];
  body.replaceChildren();
  for (const n of rows) {
    const tr = el("tr");
    tr.dataset.node = n.node;
    if (n.lost) tr.className = "lost";
    tr.append(el("td", n.node), el("td", n.name || "-"), el("td", identity(n.identity)));
    let shown = n.state + (n.state_by === "NMT" ? " (by NMT command)" : "");
    if (n.lost) shown += " (lost)";
    const st = el("td", shown, "state");
    st.dataset.state = n.state;
    tr.append(st);
    let hb = n.period_ms === null ? "-" : `${n.period_ms.toFixed(0)} ms`;
    if (n.configured_ms !== null) hb += ` (0x1017: ${n.configured_ms} ms)`;
    tr.append(el("td", hb), el("td", `${n.seen_ago_s.toFixed(1)} s ago`),
              el("td", n.bootups), el("td", n.emcys));
    body.append(tr);
  }
  for (const id of ["event-node", "sdo-node", "nmt-node"]) nodeChoices($(id), rows);
}

function nodeChoices(select, rows) {
  const have = new Set([...select.options].map((o) => o.value));
  for (const n of rows) {
    if (!have.has(String(n.node))) select.append(new Option(`node ${n.node}`, n.node));
  }
  if (select.id === "sdo-node" && state.odNode === null && select.value) loadTree();
}

function fps(groups) {
  const body = $("fps").tBodies[0];
  body.replaceChildren();
  for (const [group, rate] of Object.entries(groups)) {
    const tr = el("tr");
    tr.append(el("td", group), el("td", rate.toFixed(1)));
    body.append(tr);
  }
}

// ---- events

function kindFilters() {
  const box = $("event-kinds");
  for (const kind of KINDS) {
    const label = el("label");
    const cb = el("input");
    cb.type = "checkbox";
    cb.checked = true;
    cb.value = kind;
    cb.addEventListener("change", filterEvents);
    label.append(cb, " " + kind);
    box.append(label);
  }
  $("event-node").addEventListener("change", filterEvents);
}

function eventShown(li) {
  const node = $("event-node").value;
  const kinds = new Set([...$("event-kinds").querySelectorAll("input:checked")]
    .map((c) => c.value));
  return kinds.has(li.dataset.kind) && (!node || li.dataset.node === node);
}

function filterEvents() {
  for (const li of $("events").children) li.hidden = !eventShown(li);
}

function events(list) {
  const ol = $("events");
  for (const [t, kind, node, text] of list) {
    const li = el("li", null, `kind-${kind}`);
    li.dataset.kind = kind;
    li.dataset.node = node === null ? "" : String(node);
    li.append(el("time", clock(t)), el("span", kind, "kind"), el("span", text, "text"));
    li.hidden = !eventShown(li);
    ol.prepend(li);
  }
  while (ol.children.length > MAX_EVENTS) ol.lastChild.remove();
}

// ---- raw frames

function frameMatches(f, filter) {
  if (!filter) return true;
  const [, id, , , kind, node, text] = f;
  const words = filter.toLowerCase().split(",").map((w) => w.trim()).filter(Boolean);
  return words.some((w) => {
    const m = w.match(/^node\s+(\d+)$/);
    if (m) return node === Number(m[1]);
    if (/^(0x)?[0-9a-f]{1,8}$/.test(w) && parseInt(w, 16) === id) return true;
    return kind === w || text.toLowerCase().includes(w);
  });
}

function frames(list) {
  if ($("raw-pause").checked) return;
  const body = $("raw").tBodies[0];
  const filter = $("raw-filter").value.trim();
  for (const f of list) {
    if (!frameMatches(f, filter)) continue;
    const [t, id, data, ext] = f;
    const tr = el("tr");
    tr.dataset.id = id;
    tr.append(el("td", clock(t)), el("td", id.toString(16).toUpperCase()
      .padStart(ext ? 8 : 3, "0")), el("td", data), el("td", f[6]));
    body.prepend(tr);
  }
  while (body.children.length > MAX_FRAMES) body.lastChild.remove();
}

function leftOut(left) {
  for (const k of ["events", "frames", "points"]) state.left[k] += left[k];
  $("frames-left").textContent = state.left.frames ? `${state.left.frames} frames not ` +
    "listed here (the page is sent at most a few hundred a second; every frame is counted " +
    "in the figures above)" : "";
  $("events-left").textContent = state.left.events ?
    `${state.left.events} older events not sent to this page` : "";
  $("points-left").textContent = state.left.points ? `${state.left.points} points thinned ` +
    "for display (every n-th kept, the newest always)" : "";
}

// ---- signals

function signalLabel(s) {
  return `node ${s.node} ${s.pdo} ${s.name}` + (s.unit ? ` [${s.unit}]` : "");
}

function signalList(list) {
  const box = $("signal-list");
  $("no-signals").hidden = list.length > 0;
  for (const s of list) {
    if (state.signals.has(s.id)) continue;
    state.signals.set(s.id, s);
    state.series.set(s.id, {t: [], v: []});
    const label = el("label");
    const cb = el("input");
    cb.type = "checkbox";
    cb.value = s.id;
    cb.addEventListener("change", () => select(s.id, cb.checked));
    label.append(cb, " " + signalLabel(s));
    box.append(label);
    if (state.autoSelected < 4) {  // the first few are shown at once
      state.autoSelected += 1;
      cb.checked = true;
      select(s.id, true);
    }
  }
}

function select(id, on) {
  if (on) {
    state.selected.add(id);
    chart(id);
  } else {
    state.selected.delete(id);
    const c = state.charts.get(id);
    if (c) { c.plot.destroy(); c.card.remove(); state.charts.delete(id); }
  }
}

function chart(id) {
  const s = state.signals.get(id);
  const card = el("div", null, "chart");
  card.dataset.signal = id;
  const title = el("div", signalLabel(s), "chart-title");
  const last = el("span", "-", "last");
  last.dataset.signal = id;
  title.append(" last: ", last);
  const area = el("div");
  card.append(title, area);
  $("charts").append(card);
  const color = COLORS[state.charts.size % COLORS.length];
  const plot = new uPlot({
    width: Math.max(300, $("charts").clientWidth - 20), height: 160,
    scales: {x: {time: true}},
    series: [{}, {label: s.name, stroke: color, width: 1.5,
      value: (u, v) => (v === null || v === undefined ? "-" : `${v} ${s.unit}`.trim())}],
    axes: [{}, {size: 60}],
  }, [[], []], area);
  state.charts.set(id, {plot, card, last});
  draw(id);
}

function points(byId) {
  for (const [id, [ts, vs]] of Object.entries(byId)) {
    const s = state.series.get(id);
    if (!s) continue;
    for (let i = 0; i < ts.length; i++) { s.t.push(ts[i]); s.v.push(vs[i]); }
    const cut = s.t.length ? s.t[s.t.length - 1] - KEEP_S : 0;
    let drop = 0;
    while (drop < s.t.length && s.t[drop] < cut) drop++;
    if (drop) { s.t.splice(0, drop); s.v.splice(0, drop); }
  }
  if (!state.paused) for (const id of state.charts.keys()) draw(id);
}

function draw(id) {
  const c = state.charts.get(id);
  const s = state.series.get(id);
  if (!c || !s || !s.t.length) return;
  const to = Math.max(state.now, s.t[s.t.length - 1]);  // a silent signal's line stops
  const from = to - Number($("window").value);
  let i = 0;
  while (i < s.t.length && s.t[i] < from) i++;
  c.plot.batch(() => {
    c.plot.setData([s.t.slice(i), s.v.slice(i)], false);
    c.plot.setScale("x", {min: from, max: to});
  });
  const sig = state.signals.get(id);
  c.last.textContent = `${s.v[s.v.length - 1]} ${sig.unit}`.trim();
  c.last.dataset.value = String(s.v[s.v.length - 1]);
}

// ---- SDO browser and NMT

async function api(path, body) {
  const r = await fetch(path, {
    method: body === undefined ? "GET" : "POST",
    headers: {"Content-Type": "application/json", "X-Canola-Token": token},
    body: body === undefined ? undefined : JSON.stringify(body),
  });
  const data = await r.json();
  if (!r.ok) throw new Error(data.error || `HTTP ${r.status}`);
  return data;
}

function result(p, ok, text) {
  p.textContent = text;
  p.className = ok ? "ok" : "bad";
}

async function loadTree() {
  const node = $("sdo-node").value;
  if (!node) return;
  state.odNode = node;
  try {
    state.od = await api(`/api/od/${node}`);
  } catch (e) {
    state.od = {objects: [], file: null};
    result($("sdo-result"), false, e.message);
  }
  $("od-file").textContent = state.od.file ? `EDS: ${state.od.file}` :
    "no EDS/DCF for this node (--eds): entries by address, values as hex";
  tree();
}

function tree() {
  const box = $("od-tree");
  box.replaceChildren();
  const find = $("od-filter").value.trim().toLowerCase();
  for (const obj of state.od.objects) {
    const idx = hex(obj.index, 4);
    const hit = (sub) => !find || idx.toLowerCase().includes(find) ||
      obj.name.toLowerCase().includes(find) || (sub && sub.name.toLowerCase().includes(find));
    if (!hit(null) && !obj.subs.some(hit)) continue;
    const det = el("details");
    det.dataset.index = obj.index;
    const sum = el("summary");
    sum.append(el("code", idx), " ", el("span", obj.name, "od-name"));
    det.append(sum);
    for (const sub of obj.subs) {
      const row = el("div", null, "od-entry");
      row.dataset.index = obj.index;
      row.dataset.sub = sub.sub;
      row.append(el("code", `:${sub.sub}`), " ", el("span", sub.name, "od-name"), " ",
                 el("span", `${sub.type} ${sub.access}`, "od-type"));
      row.addEventListener("click", () => {
        $("sdo-entry").value = `${idx}:${sub.sub}`;
        $("sdo-entry-name").textContent = `${obj.name} / ${sub.name} (${sub.type})`;
      });
      det.append(row);
    }
    if (find) det.open = true;
    box.append(det);
  }
}

async function sdo(write) {
  const out = $("sdo-result");
  const body = {node: Number($("sdo-node").value), entry: $("sdo-entry").value.trim()};
  if (!body.node) return result(out, false, "choose a node");
  out.textContent = "…";
  out.className = "";
  try {
    if (write) {
      body.value = $("sdo-value").value;
      const r = await api("/api/sdo/write", body);
      result(out, true, `written: ${r.written}`);
    } else {
      const r = await api("/api/sdo/read", body);
      result(out, true, `${body.entry} = ${r.value}` + (r.type ? ` (${r.type})` : "") +
        `  [${r.raw}]`);
      out.dataset.value = r.value;
    }
  } catch (e) {
    result(out, false, `${write ? "write" : "read"} failed: ${e.message}`);
  }
}

async function nmt() {
  const out = $("nmt-result");
  out.textContent = "…";
  out.className = "";
  try {
    const r = await api("/api/nmt", {node: Number($("nmt-node").value),
                                     command: $("nmt-command").value});
    result(out, true, `sent: ${r.sent}`);
  } catch (e) {
    result(out, false, `NMT failed: ${e.message}`);
  }
}

async function readPdos() {
  const out = $("sdo-result");
  out.textContent = "…";
  out.className = "";
  try {
    const r = await api("/api/pdos", {node: Number($("sdo-node").value)});
    const valid = r.pdos.filter((p) => p.valid).map((p) => p.name);
    result(out, true, `PDO mappings of node ${r.node} read: ${valid.join(", ") || "none valid"}`);
  } catch (e) {
    result(out, false, `reading the PDO mappings failed: ${e.message}`);
  }
}

function start() {
  kindFilters();
  $("pause").addEventListener("click", () => {
    state.paused = !state.paused;
    $("pause").textContent = state.paused ? "resume" : "pause";
    if (!state.paused) for (const id of state.charts.keys()) draw(id);
  });
  $("window").addEventListener("change", () => { for (const id of state.charts.keys()) draw(id); });
  $("sdo-node").addEventListener("change", loadTree);
  $("od-filter").addEventListener("input", () => { if (state.od) tree(); });
  $("sdo-read").addEventListener("click", () => sdo(false));
  $("sdo-write").addEventListener("click", () => sdo(true));
  $("nmt-send").addEventListener("click", nmt);
  $("pdo-read").addEventListener("click", readPdos);
  connect();
}

document.addEventListener("DOMContentLoaded", start);
