// petrinav run viewer: draws replayed runs (the JSON in #page-data, shared
// by the runs, and in one .run-data block per run) on a canvas and shows
// the current tick's notes. Hand-written, no library.
// State for tests and scripts: <body data-ready data-runs data-run
// data-run-key data-tick data-time data-robot-x data-robot-y
// data-robot-page-x data-robot-page-y>.
// URL hash: #run=K (from 0), t=SECONDS, tick=N, play=1, speed=K.
"use strict";
// A block's JSON, zlib-compressed and in base64 (data-encoding), or plain.
async function petrinavInflate(el) {
  if (el.dataset.encoding !== "zlib+base64") return JSON.parse(el.textContent);
  const bin = atob(el.textContent.trim());
  const bytes = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
  const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream("deflate"));
  return JSON.parse(await new Response(stream).text());
}
petrinavInflate(document.getElementById("page-data"))
  .then(petrinavViewer)
  .catch((e) => console.error("the viewer failed: " + (e && e.message ? e.message : e)));

function petrinavViewer(P) {
  const blocks = document.querySelectorAll("script.run-data");
  const R = blocks.length;
  if (R === 0) throw new Error("the page has no run");
  const loaded = [];
  // Each run is inflated when first chosen.
  const loadRun = (k) => (loaded[k] = loaded[k] || petrinavInflate(blocks[k]));
  let D = null, T = null, N = 0, run = -1;
  const $ = (id) => document.getElementById(id);
  const canvas = $("map");
  const ctx = canvas.getContext("2d");
  const slider = $("slider");
  const PALETTE = ["#1f77b4", "#ff7f0e", "#2ca02c", "#9467bd", "#8c564b", "#e377c2",
    "#17becf", "#bcbd22", "#d62728", "#7f7f7f"];
  const colourOf = (b) => (b < 0 ? "#888888" : PALETTE[b % PALETTE.length]);
  const kindColour = (kind) => {
    const m = P.markers[kind];
    if (m) return m.colour;
    let h = 0;
    for (const c of kind) h = (h * 31 + c.charCodeAt(0)) >>> 0;
    return PALETTE[h % PALETTE.length];
  };
  const fmt = (v, d) => (v === null || v === undefined ? "–" : Number(v).toFixed(d));
  const num = (v) => (typeof v === "number" ? String(Number(v.toPrecision(4))) : String(v));

  let cur = 0, playing = false, speed = 1, timer = null, carry = 0;
  let zoom = 1, centre = null, follow = false, drag = null;
  // The maps, decoded once each.
  const images = P.maps.map((m) => {
    const img = new Image();
    img.ready = false;
    img.onload = () => { img.ready = true; if (D) draw(); };
    img.onerror = () => console.error("the viewer failed: the map image could not be decoded");
    img.src = m.png;
    return img;
  });

  // ---- geometry -------------------------------------------------------
  const V = P.view;
  let W = 0, H = 0, S = 1;
  function layout() {
    W = Math.max(200, canvas.parentElement.clientWidth);
    const aspect = (V[3] - V[1]) / Math.max(1e-9, V[2] - V[0]);
    H = Math.round(Math.min(Math.max(240, W * aspect), Math.max(320, window.innerHeight - 170)));
    canvas.width = W;
    canvas.height = H;
  }
  function scale() {
    return Math.min(W / (V[2] - V[0]), H / (V[3] - V[1])) * 0.98 * zoom;
  }
  function viewCentre() {
    if (follow) return [T.pose[cur][0], T.pose[cur][1]];
    return centre || [(V[0] + V[2]) / 2, (V[1] + V[3]) / 2];
  }
  function px(x, y) {
    const c = viewCentre();
    return [W / 2 + (x - c[0]) * S, H / 2 - (y - c[1]) * S];
  }
  function mountToWorld(p, m) {
    const c = Math.cos(p[2]), s = Math.sin(p[2]);
    return [p[0] + c * m[0] - s * m[1], p[1] + s * m[0] + c * m[1], p[2] + m[2]];
  }

  // ---- drawing --------------------------------------------------------
  function circle(x, y, r, fill, stroke, width, dash) {
    const [X, Y] = px(x, y);
    ctx.beginPath();
    ctx.arc(X, Y, Math.max(1.5, r * S), 0, 2 * Math.PI);
    if (fill) { ctx.fillStyle = fill; ctx.fill(); }
    if (stroke) {
      ctx.setLineDash(dash || []);
      ctx.strokeStyle = stroke; ctx.lineWidth = width || 1; ctx.stroke();
      ctx.setLineDash([]);
    }
  }
  function line(a, b, colour, width) {
    const [X0, Y0] = px(a[0], a[1]), [X1, Y1] = px(b[0], b[1]);
    ctx.beginPath(); ctx.moveTo(X0, Y0); ctx.lineTo(X1, Y1);
    ctx.strokeStyle = colour; ctx.lineWidth = width || 1; ctx.stroke();
  }
  function marker(at, kind, big) {
    const m = P.markers[kind];
    const shape = m ? m.shape : "square";
    const colour = kindColour(kind);
    const [X, Y] = px(at[0], at[1]);
    const k = big ? 1.6 : 1;
    ctx.lineWidth = 2;
    if (shape === "ring" || shape === "goal") {
      ctx.beginPath(); ctx.arc(X, Y, 7 * k, 0, 2 * Math.PI);
      ctx.strokeStyle = colour; ctx.stroke();
      ctx.beginPath(); ctx.arc(X, Y, 2 * k, 0, 2 * Math.PI);
      ctx.fillStyle = colour; ctx.fill();
    } else {
      const h = (shape === "point" ? 2.5 : 3.5) * k;
      ctx.fillStyle = colour; ctx.fillRect(X - h, Y - h, 2 * h, 2 * h);
      ctx.strokeStyle = "#ffffff"; ctx.lineWidth = 1; ctx.strokeRect(X - h, Y - h, 2 * h, 2 * h);
    }
  }
  function drawMap() {
    ctx.fillStyle = "#cdcdcd";
    ctx.fillRect(0, 0, W, H);
    const img = images[D.map];
    if (!img.ready) return;
    const c = viewCentre(), m = P.maps[D.map];
    ctx.save();
    ctx.setTransform(S, 0, 0, -S, W / 2 - c[0] * S, H / 2 + c[1] * S);
    ctx.translate(m.origin[0], m.origin[1]);
    ctx.rotate(m.origin[2]);
    ctx.translate(0, m.height * m.resolution_m);
    ctx.scale(m.resolution_m, -m.resolution_m);
    ctx.imageSmoothingEnabled = false;
    ctx.drawImage(img, 0, 0);
    ctx.restore();
  }
  function drawPath() {
    ctx.lineJoin = "round";
    ctx.beginPath();
    for (let k = 0; k < N; k++) {
      const [X, Y] = px(T.pose[k][0], T.pose[k][1]);
      if (k === 0) ctx.moveTo(X, Y); else ctx.lineTo(X, Y);
    }
    ctx.strokeStyle = "rgba(0,0,0,0.18)"; ctx.lineWidth = 1; ctx.setLineDash([3, 3]); ctx.stroke();
    ctx.setLineDash([]);
    let k = 0;
    while (k < cur) {
      const b = T.behaviour[k];
      ctx.beginPath();
      let [X, Y] = px(T.pose[k][0], T.pose[k][1]);
      ctx.moveTo(X, Y);
      while (k < cur && T.behaviour[k] === b) {
        k++;
        [X, Y] = px(T.pose[k][0], T.pose[k][1]);
        ctx.lineTo(X, Y);
      }
      ctx.strokeStyle = colourOf(b); ctx.lineWidth = 2.5; ctx.stroke();
    }
  }
  function drawSensors(p) {
    const r = T.readings[cur];
    if (!r) return;
    const g = D.geometries[r.g];
    (r.laser || []).forEach((ranges, l) => {
      const G = g.lasers[l], m = mountToWorld(p, G.mount);
      ctx.fillStyle = "rgba(220,30,30,0.85)";
      for (let i = 0; i < ranges.length; i++) {
        if (ranges[i] < 0) continue;
        const a = m[2] + G.angle_min + i * G.angle_increment, d = ranges[i] / 100;
        const e = [m[0] + d * Math.cos(a), m[1] + d * Math.sin(a)];
        line(m, e, "rgba(220,30,30,0.18)", 1);
        const [X, Y] = px(e[0], e[1]);
        ctx.fillRect(X - 1.5, Y - 1.5, 3, 3);
      }
    });
    (r.sonar || []).forEach((range, i) => {
      const G = g.sonar[i], m = mountToWorld(p, G.mount);
      if (range < 0) return;
      const [X, Y] = px(m[0], m[1]);
      ctx.beginPath(); ctx.moveTo(X, Y);
      ctx.arc(X, Y, (range / 100) * S, -(m[2] + G.cone / 2), -(m[2] - G.cone / 2));
      ctx.closePath();
      ctx.fillStyle = "rgba(30,100,220,0.15)"; ctx.fill();
      ctx.strokeStyle = "rgba(30,100,220,0.7)"; ctx.lineWidth = 1; ctx.stroke();
    });
    (r.ir || []).forEach((on, i) => {
      const G = g.ir[i], m = mountToWorld(p, G.mount);
      const e = [m[0] + G.range * Math.cos(m[2]), m[1] + G.range * Math.sin(m[2])];
      line(m, e, on ? "rgba(220,20,20,0.9)" : "rgba(20,150,60,0.45)", on ? 2 : 1);
    });
  }
  // The latest cloud of each name at or before the current tick.
  function cloudsNow() {
    const latest = {};
    for (const c of D.clouds || []) {
      if (c.tick > cur) break;
      latest[c.name] = c;
    }
    return Object.values(latest);
  }
  function drawClouds() {
    ctx.fillStyle = "rgba(0,150,150,0.8)";
    let drawn = 0;
    for (const c of cloudsNow()) {
      drawn += c.points.length / 2;
      for (let i = 0; i + 1 < c.points.length; i += 2) {
        const [X, Y] = px(c.points[i] / 100, c.points[i + 1] / 100);
        ctx.fillRect(X - 1, Y - 1, 2, 2);
      }
    }
    document.body.dataset.cloudPoints = String(drawn);
  }
  function draw() {
    if (!D) return;
    layoutIfNeeded();
    S = scale();
    drawMap();
    drawPath();
    if (D.goal) {
      const [X, Y] = px(D.goal[0], D.goal[1]);
      ctx.beginPath(); ctx.arc(X, Y, 8, 0, 2 * Math.PI);
      ctx.moveTo(X - 5, Y - 5); ctx.lineTo(X + 5, Y + 5); ctx.moveTo(X + 5, Y - 5); ctx.lineTo(X - 5, Y + 5);
      ctx.strokeStyle = "#d21e1e"; ctx.lineWidth = 2; ctx.stroke();
    }
    circle(D.start[0], D.start[1], 0.08, "#28a03c", "#ffffff", 1);
    for (const e of D.events) {
      if (e.tick > cur) break;
      if (e.at) marker(e.at, e.kind, e.tick === cur);
    }
    const people = T.people[cur] || [];
    for (let i = 0; i + 1 < people.length; i += 2) {
      circle(people[i] / 100, people[i + 1] / 100, P.person_radius_m, "rgba(240,150,30,0.75)", "#a05a00", 1);
    }
    const p = T.pose[cur], q = T.estimate[cur];
    drawClouds();
    drawSensors(p);
    if (T.request[cur]) circle(p[0], p[1], T.request[cur], null, "#e07000", 1.5, [6, 4]);
    if (Math.hypot(p[0] - q[0], p[1] - q[1]) > 0.01 || Math.abs(p[2] - q[2]) > 0.01) {
      circle(q[0], q[1], D.robot_radius_m, null, "#7a3fb0", 1.5, [4, 3]);
      const r = D.robot_radius_m;
      line([q[0], q[1]], [q[0] + r * Math.cos(q[2]), q[1] + r * Math.sin(q[2])], "#7a3fb0", 1.5);
    }
    const bumped = T.contact[cur] || (T.readings[cur] && T.readings[cur].bumper);
    circle(p[0], p[1], D.robot_radius_m, "rgba(60,120,220,0.35)", bumped ? "#e01010" : "#1a4fa0", bumped ? 3 : 2);
    const r = D.robot_radius_m;
    line([p[0], p[1]], [p[0] + r * Math.cos(p[2]), p[1] + r * Math.sin(p[2])], "#0b2a60", 2);
    const [X, Y] = px(p[0], p[1]);
    const rect = canvas.getBoundingClientRect();
    const b = document.body.dataset;
    b.tick = String(cur);
    b.time = String(T.t[cur]);
    b.robotX = String(p[0]);
    b.robotY = String(p[1]);
    b.robotPageX = String(Math.round(rect.left + window.scrollX + X));
    b.robotPageY = String(Math.round(rect.top + window.scrollY + Y));
    b.playing = playing ? "1" : "0";
    b.run = String(run);
    b.runKey = D.key;
    if (images[D.map].ready) b.ready = "1";
  }
  let laidOut = false;
  function layoutIfNeeded() {
    if (!laidOut) { layout(); laidOut = true; }
  }
  window.addEventListener("resize", () => { laidOut = false; if (D) draw(); });

  // ---- panel ----------------------------------------------------------
  let valueRows = [];
  function buildPanel() {
    $("summary").textContent = D.summary;
    document.title = (R > 1 ? D.key : P.title) + " — " + P.suite + " — petrinav run viewer";
    for (const id of ["legend", "values", "events", "record"]) $(id).textContent = "";
    valueRows = [];
    const legend = $("legend");
    // The page's behaviours (one colour each on every run) that this run
    // has.
    const has = new Set(T.behaviour);
    P.behaviours.forEach((b, i) => {
      if (!has.has(i)) return;
      const s = document.createElement("span");
      s.innerHTML = '<i style="background:' + colourOf(i) + '"></i>';
      s.appendChild(document.createTextNode(b));
      legend.appendChild(s);
    });
    const kinds = {};
    for (const e of D.events) kinds[e.kind] = (kinds[e.kind] || 0) + 1;
    for (const k of Object.keys(kinds).sort()) {
      const s = document.createElement("span");
      s.innerHTML = '<b style="background:' + kindColour(k) + '"></b>';
      s.appendChild(document.createTextNode(k + " ×" + kinds[k]));
      legend.appendChild(s);
    }
    const vt = $("values");
    $("values-box").hidden = D.keys.length === 0;
    D.keys.forEach((k, i) => {
      let lo = 0, hi = 0;
      for (const row of T.values) {
        const v = row[i];
        if (v !== null) { lo = Math.min(lo, v); hi = Math.max(hi, v); }
      }
      const tr = document.createElement("tr");
      tr.innerHTML = "<td></td><td></td><td class=barcell><div class=bar></div></td>";
      tr.children[0].textContent = k;
      vt.appendChild(tr);
      valueRows.push({ value: tr.children[1], bar: tr.children[2].firstChild, lo, hi });
    });
    const list = $("events");
    $("events-box").hidden = D.events.length === 0;
    D.events.forEach((e) => {
      const li = document.createElement("li");
      li.textContent = fmt(e.t, 1) + " s  " + e.kind + payloadText(e);
      li.style.borderLeftColor = kindColour(e.kind);
      li.addEventListener("click", () => go(e.tick));
      list.appendChild(li);
    });
    const rt = $("record");
    for (const [k, v] of D.record) {
      const tr = document.createElement("tr");
      tr.innerHTML = "<td></td><td></td>";
      tr.children[0].textContent = k;
      tr.children[1].textContent = num(v);
      rt.appendChild(tr);
    }
    buildNet();
    slider.max = String(Math.max(0, N - 1));
  }
  // ---- the net beside the map ------------------------------------------
  // The run's net (D.net): places with their tokens from the values named
  // in place.value, transitions, arcs; the last event of kind D.net.event
  // played so far, with its payload.
  const SVG = "http://www.w3.org/2000/svg";
  let netPlaces = [];
  function svgEl(tag, attrs, parent) {
    const el = document.createElementNS(SVG, tag);
    for (const [k, v] of Object.entries(attrs)) el.setAttribute(k, String(v));
    parent.appendChild(el);
    return el;
  }
  function buildNet() {
    const box = $("net-box"), svg = $("net");
    svg.textContent = "";
    netPlaces = [];
    box.hidden = !D.net;
    if (!D.net) return;
    const net = D.net;
    $("net-title").textContent = "Net: " + net.name;
    const nodes = net.places.concat(net.transitions);
    let x0 = Infinity, y0 = Infinity, x1 = -Infinity, y1 = -Infinity;
    for (const n of nodes) {
      x0 = Math.min(x0, n.x); y0 = Math.min(y0, n.y); x1 = Math.max(x1, n.x); y1 = Math.max(y1, n.y);
    }
    const pad = 24;
    svg.setAttribute("viewBox", (x0 - pad) + " " + (y0 - pad) + " " + (x1 - x0 + 2 * pad) + " " + (y1 - y0 + 2 * pad));
    for (const a of net.arcs) {
      const p = net.places[a.place], t = net.transitions[a.transition];
      svgEl("line", { x1: p.x, y1: p.y, x2: t.x, y2: t.y, class: "arc " + a.kind }, svg);
    }
    for (const t of net.transitions) {
      const r = svgEl("rect", t.immediate
        ? { x: t.x - 2, y: t.y - 9, width: 4, height: 18, class: "transition immediate" }
        : { x: t.x - 5, y: t.y - 9, width: 10, height: 18, class: "transition" }, svg);
      svgEl("title", {}, r).textContent = t.name + (t.doc ? ": " + t.doc : "");
    }
    for (const p of net.places) {
      const c = svgEl("circle", { cx: p.x, cy: p.y, r: 12, class: "place" }, svg);
      svgEl("title", {}, c).textContent = p.name + (p.doc ? ": " + p.doc : "");
      const label = svgEl("text", { x: p.x, y: p.y - 16 }, svg);
      label.textContent = p.name;
      const token = svgEl("circle", { cx: p.x, cy: p.y, r: 4, class: "token" }, svg);
      netPlaces.push({ name: p.name, key: D.keys.indexOf(p.value), circle: c, token });
    }
  }
  function updateNet() {
    if (!D.net) return;
    const row = T.values[cur] || [];
    const marked = [];
    for (const p of netPlaces) {
      const v = p.key < 0 ? null : row[p.key];
      const on = v !== null && v !== undefined && v > 0;
      p.circle.setAttribute("class", on ? "place marked" : "place");
      p.token.style.display = on ? "" : "none";
      if (on) marked.push(p.name);
    }
    let last = null;
    for (const e of D.events) {
      if (e.tick > cur) break;
      if (e.kind === D.net.event) last = e;
    }
    const table = $("net-event");
    table.textContent = "";
    const row2 = (k, v) => {
      const tr = document.createElement("tr");
      tr.innerHTML = "<td></td><td></td>";
      tr.children[0].textContent = k;
      tr.children[1].textContent = v;
      table.appendChild(tr);
    };
    if (last) {
      row2("last " + D.net.event, fmt(last.t, 1) + " s");
      for (const [k, v] of Object.entries(last.payload || {})) row2(k, num(v));
    } else {
      row2("last " + D.net.event, "none yet");
    }
    document.body.dataset.netMarking = marked.join(" ");
    document.body.dataset.netEventTick = last ? String(last.tick) : "-1";
  }
  function payloadText(e) {
    if (!e.payload) return "";
    return " · " + Object.entries(e.payload).map(([k, v]) => k + " " + num(v)).join(", ");
  }
  function setRow(id, text) { $(id).textContent = text; }
  function updatePanel() {
    const p = T.pose[cur], q = T.estimate[cur];
    setRow("clock", "t = " + fmt(T.t[cur], 1) + " s · tick " + cur + " / " + (N - 1));
    const b = T.behaviour[cur];
    $("behaviour").innerHTML = '<i style="background:' + colourOf(b) + '"></i>';
    $("behaviour").appendChild(document.createTextNode(b < 0 ? "–" : P.behaviours[b]));
    setRow("step", T.step[cur] + (T.contact[cur] ? " · contact" : ""));
    const c = T.command[cur];
    setRow("command", !c ? "none" : c[0] === "stop" ? "stop"
      : c[0] === "twist" ? "v " + fmt(c[1], 2) + " m/s, ω " + fmt(c[2], 2) + " rad/s"
      : "wheels " + fmt(c[1], 2) + " / " + fmt(c[2], 2) + " m/s");
    setRow("wheels", fmt(T.wheels[cur][0], 2) + " / " + fmt(T.wheels[cur][1], 2) + " m/s");
    setRow("pose", fmt(p[0], 2) + ", " + fmt(p[1], 2) + " m, " + fmt(p[2], 2) + " rad");
    setRow("estimate", fmt(q[0], 2) + ", " + fmt(q[1], 2) + " m, " + fmt(q[2], 2) + " rad");
    setRow("request", T.request[cur] ? "step aside within " + fmt(T.request[cur], 2) + " m" : "–");
    const row = T.values[cur] || [];
    valueRows.forEach((r, i) => {
      const v = row[i];
      r.value.textContent = v === null || v === undefined ? "–" : num(v);
      const span = r.hi - r.lo;
      if (v === null || v === undefined || span <= 0) { r.bar.style.width = "0"; return; }
      const zero = (0 - r.lo) / span, at = (v - r.lo) / span;
      r.bar.style.marginLeft = (Math.min(zero, at) * 100).toFixed(1) + "%";
      r.bar.style.width = (Math.abs(at - zero) * 100).toFixed(1) + "%";
      r.bar.className = v < 0 ? "bar neg" : "bar";
    });
    setRow("sensors", sensorText());
    $("cloud-row").hidden = !(D.clouds && D.clouds.length);
    setRow("cloud", cloudsNow().map((c) => c.name + " " + c.size + " (tick " + c.tick + ", " +
      (c.points.length / 2) + " drawn)").join(" · ") || "–");
    const now = $("now");
    now.textContent = "";
    for (const e of D.events) {
      if (e.tick !== cur) continue;
      const li = document.createElement("li");
      li.textContent = e.kind + payloadText(e);
      li.style.borderLeftColor = kindColour(e.kind);
      now.appendChild(li);
    }
    if (!now.firstChild) now.innerHTML = "<li class=none>none</li>";
    const items = $("events").children;
    for (let i = 0; i < items.length; i++) {
      items[i].className = D.events[i].tick === cur ? "now" : D.events[i].tick < cur ? "past" : "";
    }
    updateNet();
    slider.value = String(cur);
    $("play").textContent = playing ? "❚❚ pause" : "▶ play";
  }
  function sensorText() {
    const r = T.readings[cur];
    if (!r) return "not recorded";
    const out = [];
    (r.laser || []).forEach((ranges, l) => {
      let best = -1;
      for (let i = 0; i < ranges.length; i++) if (ranges[i] >= 0 && (best < 0 || ranges[i] < ranges[best])) best = i;
      const G = D.geometries[r.g].lasers[l];
      const hits = ranges.filter((x) => x >= 0).length;
      out.push("laser: " + hits + "/" + ranges.length + " returns" + (best < 0 ? ""
        : ", nearest " + fmt(ranges[best] / 100, 2) + " m at " + fmt(G.angle_min + best * G.angle_increment, 2) + " rad"));
    });
    if (r.sonar) out.push("sonar (m): " + r.sonar.map((x) => (x < 0 ? "∞" : fmt(x / 100, 2))).join(" "));
    if (r.ir) out.push("IR: " + r.ir.map((x) => (x ? "●" : "○")).join(""));
    if (r.bumper) out.push("bumper pressed");
    return out.join("\n") || "no sensors";
  }

  // ---- time -----------------------------------------------------------
  function go(k) {
    cur = Math.max(0, Math.min(N - 1, Math.round(k)));
    draw();
    updatePanel();
  }
  function tickAt(t) {
    let k = 0;
    while (k + 1 < N && T.t[k + 1] <= t + 1e-9) k++;
    return k;
  }
  function setPlaying(on, quiet) {
    playing = on && N > 1;
    if (timer) { clearInterval(timer); timer = null; }
    if (quiet) return;
    if (playing) {
      if (cur >= N - 1) cur = 0;
      carry = 0;
      timer = setInterval(() => {
        carry += (0.04 * speed) / D.dt_s;
        const n = Math.floor(carry);
        carry -= n;
        if (n > 0) go(cur + n);
        if (cur >= N - 1) setPlaying(false);
      }, 40);
    }
    draw();
    updatePanel();
  }
  // The run k: its data inflated, the panel rebuilt, the slider at 0.
  async function chooseRun(k) {
    const data = await loadRun(k);
    setPlaying(false, true);
    D = data; T = D.ticks; N = T.t.length; run = k; cur = 0;
    if (N === 0) throw new Error("run " + D.key + " has no ticks");
    $("run").value = String(k);
    buildPanel();
  }
  let hashes = 0;
  async function readHash() {
    const mine = ++hashes;
    const h = new URLSearchParams(location.hash.replace(/^#/, ""));
    const k = h.has("run") ? Math.max(0, Math.min(R - 1, Math.round(Number(h.get("run")) || 0))) : Math.max(0, run);
    if (k !== run) {
      await chooseRun(k);
      if (mine !== hashes) return;
    }
    if (h.has("speed")) { speed = Math.max(0.1, Number(h.get("speed")) || 1); $("speed").value = String(speed); }
    if (h.has("tick")) cur = Math.max(0, Math.min(N - 1, Number(h.get("tick")) || 0));
    else if (h.has("t")) cur = tickAt(Number(h.get("t")) || 0);
    setPlaying(h.get("play") === "1");
  }
  // Another run: through the URL, so that it can be shared and reloaded.
  function goRun(k) {
    k = Math.max(0, Math.min(R - 1, k));
    if (k !== run) location.hash = "run=" + k;
  }

  // ---- input ----------------------------------------------------------
  slider.addEventListener("input", () => { setPlaying(false); go(Number(slider.value)); });
  $("play").addEventListener("click", () => setPlaying(!playing));
  $("run").addEventListener("change", () => goRun(Number($("run").value)));
  $("prev-run").addEventListener("click", () => goRun(run - 1));
  $("next-run").addEventListener("click", () => goRun(run + 1));
  $("prev").addEventListener("click", () => { setPlaying(false); go(cur - 1); });
  $("next").addEventListener("click", () => { setPlaying(false); go(cur + 1); });
  $("speed").addEventListener("change", () => { speed = Number($("speed").value); });
  $("follow").addEventListener("change", () => { follow = $("follow").checked; draw(); });
  $("reset").addEventListener("click", () => { zoom = 1; centre = null; draw(); });
  document.addEventListener("keydown", (e) => {
    if (!D || e.target.tagName === "SELECT") return;
    const big = e.shiftKey ? Math.round(1 / D.dt_s) : 1;
    if (e.key === " ") setPlaying(!playing);
    else if (e.key === "ArrowRight") { setPlaying(false); go(cur + big); }
    else if (e.key === "ArrowLeft") { setPlaying(false); go(cur - big); }
    else if (e.key === "Home") { setPlaying(false); go(0); }
    else if (e.key === "End") { setPlaying(false); go(N - 1); }
    else if (e.key === "[") goRun(run - 1);
    else if (e.key === "]") goRun(run + 1);
    else if (e.key === "+" || e.key === "=") { zoom *= 1.5; draw(); }
    else if (e.key === "-") { zoom = Math.max(0.2, zoom / 1.5); draw(); }
    else return;
    e.preventDefault();
  });
  canvas.addEventListener("wheel", (e) => {
    e.preventDefault();
    const rect = canvas.getBoundingClientRect();
    const c = viewCentre();
    const wx = c[0] + (e.clientX - rect.left - W / 2) / S, wy = c[1] - (e.clientY - rect.top - H / 2) / S;
    const f = e.deltaY < 0 ? 1.25 : 0.8;
    zoom = Math.max(0.2, zoom * f);
    const S2 = scale();
    centre = [wx - (e.clientX - rect.left - W / 2) / S2, wy + (e.clientY - rect.top - H / 2) / S2];
    draw();
  }, { passive: false });
  canvas.addEventListener("mousedown", (e) => { drag = [e.clientX, e.clientY, viewCentre()]; });
  window.addEventListener("mouseup", () => { drag = null; });
  window.addEventListener("mousemove", (e) => {
    if (!drag) return;
    centre = [drag[2][0] - (e.clientX - drag[0]) / S, drag[2][1] + (e.clientY - drag[1]) / S];
    follow = false; $("follow").checked = false;
    draw();
  });
  canvas.addEventListener("dblclick", () => { zoom = 1; centre = null; draw(); });
  const failed = (e) => console.error("the viewer failed: " + (e && e.message ? e.message : e));
  window.addEventListener("hashchange", () => readHash().catch(failed));
  return readHash();
}
