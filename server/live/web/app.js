// SAGE Fleet's live view: the fleet on the seabed, drawn on a canvas every animation frame from
// the frames the mission's server pushes (Server-Sent Events, about ten a second) or, for a
// recorded mission (sage view), from the frame of the time the slider or play asks for.
// Everything the server sends is data: names and texts go into the page as text, never as HTML.
// The mission's token comes from the address's fragment (#token=...), which the browser never
// sends to any server; it goes with every request as X-Sage-Token (or ?token= for the stream).
"use strict";

(() => {
  const $ = (id) => document.getElementById(id);
  const STATUS = ["alive", "stale", "lost", "left"];
  const HULL_M = 0.3;          // nose to centre: a BlueROV2 is 0.46 x 0.58 m
  const TABLE_ROWS = 100;      // valves listed at once (the filter finds the others)
  const TRAIL_S = 4;           // mission seconds of each vehicle's trail (the server's too)
  const TRAIL_POINTS = 8;
  const TABLE_PERIOD_MS = 1000; // the table and the log are rewritten at most this often
  const BACKGROUND = "#0a1622";  // app.css --bg
  // Redraws a second at most: frames come ten a second and vehicles move smoothly between them at
  // 30; more would only take CPU from the mission on the same machine. The address may ask for
  // another cap (#fps=30, 1..60).
  const fpsAsked = Number(new URLSearchParams(location.hash.slice(1)).get("fps"));
  const fpsCap = Number.isFinite(fpsAsked) && fpsAsked >= 1 && fpsAsked <= 60 ? fpsAsked : 0;
  const maxFps = () => fpsCap || (frame && frame.v.length > LARGE_FLEET ? 12 : 30);
  // Over LARGE_FLEET vehicles a live page draws on the server's clock instead: DRAWS_PER_FRAME
  // redraws a frame, the first when it arrives and the others evenly after it, none in the last
  // part of the interval. A frame leaves the server just after its cycle and the next cycle comes
  // a frame interval later, so the browser's work (a thousand vehicles rasterised in software)
  // falls between the server's cycles instead of beside them on the other core: on the 2-core
  // machine the server's cycle took 30 % more CPU with the page redrawing at 12 a second on its
  // own schedule (README, live view).
  const LARGE_FLEET = 300;
  const DRAWS_PER_FRAME = 2;
  const drawsOnFrames = () => !fpsCap && scene && scene.mode === "live" && frame && !frame.finished &&
    frame.v.length > LARGE_FLEET;

  // What the page counts, for people (the panel) and for tests (window.sageView).
  const view = {
    frames: 0,           // canvas redraws since the page opened
    fps: 0,              // redraws in the last second
    updates: 0,          // frames received from the server
    updateRate: 0,
    seq: 0,              // the last frame's number
    vehiclesShown: 0,    // vehicles the last frame holds (every status)
    vehiclesAlive: 0,
    time: 0,
    ready: false,        // the scene and a first frame are in
    lastAnswer: null,    // the last operator answer {accepted, line}
    drawMs: 0,           // a redraw's script time, and a frame's and the tables' (moving averages)
    takeMs: 0,
    tableMs: 0,
    seabedMs: 0, blitMs: 0, overlayMs: 0, vehiclesMs: 0,  // the redraw's parts
  };
  window.sageView = view;

  let token = new URLSearchParams(location.hash.slice(1)).get("token") || "";
  let scene = null;
  let frame = null;           // the latest frame
  let positions = new Map();  // id -> {x0, y0, h0, x1, y1, h1, at}: drawn between the last two frames
  let frameInterval = 100;    // ms between the last frames
  let lastFrameAt = 0;
  let drawsOfFrame = 0;       // redraws since the last frame came
  const trails = new Map();   // id -> {xy: [x, y, ...], times: [t, ...]} (live: kept here from the frames)
  let heat = null;            // {nx, ny, cell_m, canvas}
  let heatSeq = -1;
  let selectedValve = -1;
  const events = [];          // [seq, t, kind, text], oldest first
  let eventsSeen = 0;
  let sortKey = "wait", sortUp = false;
  let tableDirty = true;

  // ---------- talking to the server ----------
  async function api(path, options = {}) {
    const headers = Object.assign({ "X-Sage-Token": token }, options.headers || {});
    const response = await fetch(path, Object.assign({}, options, { headers, cache: "no-store" }));
    let body = null;
    try { body = await response.json(); } catch (e) { body = null; }
    if (!response.ok) {
      const line = body && body.line ? body.line : `HTTP ${response.status}`;
      const error = new Error(line);
      error.status = response.status;
      error.body = body;
      throw error;
    }
    return body;
  }

  function setLink(text, cls) {
    const link = $("link");
    link.textContent = text;
    link.className = "badge " + (cls || "");
  }

  async function start() {
    if (!token) {
      askToken("this address has no #token=: paste the mission's token");
      return;
    }
    try {
      scene = await api("/api/scene");
    } catch (e) {
      if (e.status === 403) askToken(e.message);
      else setLink(e.message, "down");
      return;
    }
    $("token-form").hidden = true;
    setupScene();
    if (scene.mode === "live") connectStream();
    else startReplay();
  }

  function askToken(why) {
    $("actions").hidden = false;
    $("token-form").hidden = false;
    for (const id of ["risk-form", "add-form", "remove-form", "stop-form"]) $(id).hidden = true;
    showAnswer({ accepted: false, line: why });
    setLink("no token", "down");
  }

  $("token-form").addEventListener("submit", (event) => {
    event.preventDefault();
    token = $("token-input").value.trim();
    history.replaceState(null, "", "#token=" + encodeURIComponent(token));
    for (const id of ["risk-form", "add-form", "remove-form", "stop-form"]) $(id).hidden = false;
    start();
  });

  function connectStream() {
    const source = new EventSource("/api/stream?token=" + encodeURIComponent(token));
    source.onopen = () => {
      // A stream's first frame carries the server's latest events: the log starts again from
      // them (a resumed server numbers its events anew).
      events.length = 0;
      eventsSeen = 0;
      setLink("streaming", "live");
    };
    source.onmessage = (message) => {
      const next = JSON.parse(message.data);
      takeFrame(next);
      if (next.finished) {
        setLink("mission ended", "down");
        source.close();
      }
    };
    source.onerror = () => {
      if (frame && frame.finished) return;
      setLink(source.readyState === EventSource.CLOSED ? "server gone" : "reconnecting", "down");
    };
  }

  // ---------- frames ----------
  function takeFrame(next) {
    const now = performance.now();
    try {
      takeFrameAt(next, now);
    } finally {
      view.takeMs = average(view.takeMs, performance.now() - now);
    }
  }
  function takeFrameAt(next, now) {
    if (lastFrameAt > 0) frameInterval = Math.min(1000, Math.max(20, 0.7 * frameInterval + 0.3 * (now - lastFrameAt)));
    lastFrameAt = now;
    drawsOfFrame = 0;
    wake();
    const moved = new Map();
    const jump = scene.mode !== "live";  // a replay jumps where the slider goes
    for (let i = 0; i < next.v.length; i++) {
      const [id, , x, y, h] = next.v[i];
      const before = positions.get(id);
      if (before && !jump) {
        const [px, py, ph] = interpolate(before, now);
        moved.set(id, { x0: px, y0: py, h0: ph, x1: x, y1: y, h1: h, at: now });
      } else {
        moved.set(id, { x0: x, y0: y, h0: h, x1: x, y1: y, h1: h, at: now });
      }
    }
    positions = moved;
    if (next.trails) {
      // The server's trails (a stream's first frame, every replay frame): evenly spaced over the
      // last TRAIL_S of mission time.
      trails.clear();
      next.v.forEach((v, i) => {
        const xy = next.trails[i].slice();
        const n = xy.length / 2;
        const times = Array.from({ length: n }, (_, k) => next.t - TRAIL_S * (n - 1 - k) / Math.max(1, n - 1));
        trails.set(v[0], { xy, times });
      });
    } else {
      // Live: a point each TRAIL_S / TRAIL_POINTS of mission time, the last TRAIL_S of them.
      for (const [id, , x, y, , status] of next.v) {
        if (status >= 2) continue;
        let trail = trails.get(id);
        if (!trail) trails.set(id, (trail = { xy: [], times: [] }));
        const last = trail.times.length ? trail.times[trail.times.length - 1] : -1e9;
        if (next.t - last >= TRAIL_S / TRAIL_POINTS) {
          trail.xy.push(x, y);
          trail.times.push(next.t);
        }
        let old = 0;
        while (old < trail.times.length && trail.times[old] < next.t - TRAIL_S) old++;
        if (old > 0) {
          trail.times.splice(0, old);
          trail.xy.splice(0, 2 * old);
        }
      }
    }
    for (const e of next.events || []) {
      if (e[0] > eventsSeen) {
        events.push(e);
        eventsSeen = e[0];
      }
    }
    if (scene.mode !== "live" && next.events) {
      // A replay's log is the record's up to the frame: taken whole each time.
      events.length = 0;
      for (const e of next.events) events.push(e);
      eventsSeen = next.events_total;
    }
    if (events.length > 500) events.splice(0, events.length - 500);
    frame = next;
    view.updates++;
    view.seq = next.seq;
    view.vehiclesShown = next.v.length;
    view.vehiclesAlive = next.counts.alive;
    view.time = next.t;
    view.ready = true;
    if (next.heat_seq !== heatSeq) loadHeat(next.heat_seq, next.t);
    tableDirty = true;
    // The panel's figures at most five times a second: each change lays the panel out again.
    if (now - lastStats >= 200 || next.finished || scene.mode !== "live") {
      lastStats = now;
      updateStats();
    }
  }
  let lastStats = 0;

  function interpolate(p, now) {
    const a = Math.min(1, Math.max(0, (now - p.at) / frameInterval));
    let dh = p.h1 - p.h0;
    while (dh > Math.PI) dh -= 2 * Math.PI;
    while (dh < -Math.PI) dh += 2 * Math.PI;
    return [p.x0 + (p.x1 - p.x0) * a, p.y0 + (p.y1 - p.y0) * a, p.h0 + dh * a];
  }

  let heatLoading = false;
  async function loadHeat(seq, t) {
    if (heatLoading) return;
    heatLoading = true;
    try {
      const h = await api(scene.mode === "live" ? "/api/heat" : "/api/heat?t=" + t);
      heatSeq = seq;
      if (!h.nx || !h.ny) { heat = null; return; }
      const bytes = Uint8Array.from(atob(h.data), (c) => c.charCodeAt(0));
      const canvas = document.createElement("canvas");
      canvas.width = h.nx;
      canvas.height = h.ny;
      const ctx = canvas.getContext("2d");
      const image = ctx.createImageData(h.nx, h.ny);
      for (let j = 0; j < h.ny; j++) {
        for (let i = 0; i < h.nx; i++) {
          const v = bytes[j * h.nx + i] / 255;
          const o = ((h.ny - 1 - j) * h.nx + i) * 4;  // row 0 is y = 0: the bottom of the image
          const [r, g, b] = heatColor(v);
          image.data[o] = r; image.data[o + 1] = g; image.data[o + 2] = b;
          image.data[o + 3] = Math.round(220 * Math.sqrt(v));
        }
      }
      ctx.putImageData(image, 0, 0);
      heat = { nx: h.nx, ny: h.ny, cell_m: h.cell_m, canvas };
    } catch (e) {
      // the next frame asks again
    } finally {
      heatLoading = false;
    }
  }

  // ---------- colours ----------
  // Risk share against the field's largest: blue (least) through yellow to red (most).
  function riskColor(u) {
    u = Math.min(1, Math.max(0, u));
    const r = u < 0.5 ? 0.2 + 1.6 * u : 1.0;
    const g = u < 0.5 ? 0.4 + 1.0 * u : 0.9 - 1.4 * (u - 0.5);
    const b = u < 0.5 ? 0.9 - 1.6 * u : 0.1;
    return `rgb(${Math.round(255 * r)},${Math.round(255 * g)},${Math.round(255 * b)})`;
  }
  function heatColor(v) {  // dark purple to orange
    return [Math.round(80 + 175 * v), Math.round(30 + 130 * v * v), Math.round(120 - 90 * v)];
  }

  // ---------- the map ----------
  const canvas = $("map");
  // Opaque: the compositor need not blend the map with what is under it.
  const ctx = canvas.getContext("2d", { alpha: false });
  let zoom = 1, panX = 0, panY = 0;  // screen = fit(world) * zoom + pan
  let dpr = 1, width = 0, height = 0;
  let fitScale = 1, fitX = 0, fitY = 0;

  function resize() {
    dpr = window.devicePixelRatio || 1;
    width = canvas.clientWidth;
    height = canvas.clientHeight;
    canvas.width = Math.max(1, Math.round(width * dpr));
    canvas.height = Math.max(1, Math.round(height * dpr));
    if (scene) {
      const margin = 24;
      fitScale = Math.min((width - 2 * margin) / scene.width_m, (height - 2 * margin) / scene.height_m);
      fitX = (width - fitScale * scene.width_m) / 2;
      fitY = (height + fitScale * scene.height_m) / 2;
    }
  }
  window.addEventListener("resize", resize);
  const scale = () => fitScale * zoom;
  const sx = (x) => fitX * zoom + panX + x * scale();
  const sy = (y) => fitY * zoom + panY - y * scale();
  const wx = (px) => (px - fitX * zoom - panX) / scale();
  const wy = (py) => (fitY * zoom + panY - py) / scale();

  canvas.addEventListener("wheel", (event) => {
    event.preventDefault();
    const mx = event.offsetX, my = event.offsetY;
    const x = wx(mx), y = wy(my);
    zoom = Math.min(400, Math.max(0.2, zoom * Math.exp(-event.deltaY * 0.0015)));
    panX = mx - fitX * zoom - x * scale();
    panY = my - fitY * zoom + y * scale();
  }, { passive: false });
  let drag = null;
  canvas.addEventListener("mousedown", (event) => {
    drag = { x: event.clientX, y: event.clientY, panX, panY, moved: false };
    canvas.classList.add("dragging");
  });
  window.addEventListener("mousemove", (event) => {
    if (!drag) return;
    panX = drag.panX + event.clientX - drag.x;
    panY = drag.panY + event.clientY - drag.y;
    if (Math.abs(event.clientX - drag.x) + Math.abs(event.clientY - drag.y) > 3) drag.moved = true;
  });
  window.addEventListener("mouseup", (event) => {
    if (drag && !drag.moved && scene && event.target === canvas) pick(event.offsetX, event.offsetY);
    drag = null;
    canvas.classList.remove("dragging");
  });
  canvas.addEventListener("dblclick", () => { zoom = 1; panX = 0; panY = 0; });
  $("heat-mode").addEventListener("change", () => { seabedKey = ""; });

  // A click takes the nearest vehicle (its id into the remove form) or valve (into the risk form).
  function pick(px, py) {
    let vehicle = null, best = -1, bestD = 12;
    for (const v of frame ? frame.v : []) {
      const p = positions.get(v[0]);
      if (!p) continue;
      const d = Math.hypot(sx(p.x1) - px, sy(p.y1) - py);
      if (d < bestD) { bestD = d; vehicle = v; }
    }
    scene.valves.forEach((v, i) => {
      const d = Math.hypot(sx(v[2]) - px, sy(v[3]) - py);
      if (d < bestD) { bestD = d; best = i; vehicle = null; }
    });
    if (vehicle) {
      $("remove-id").value = vehicle[0];
      showAnswer({ accepted: true, line: `${vehicle[1]} (id ${vehicle[0]}) ${STATUS[vehicle[5]]} at ` +
                                         `(${vehicle[2].toFixed(1)}, ${vehicle[3].toFixed(1)}) m` });
    } else if (best >= 0) {
      selectValve(best);
    }
  }

  function selectValve(i) {
    selectedValve = i;
    $("risk-valve").value = scene.valves[i][0];
    if (frame) $("risk-weight").value = frame.valves[i][0];
    tableDirty = true;
  }

  // Three layers, so that a redraw is cheap with a thousand vehicles: the seabed (workspace,
  // heat map, XTs, valves and their labels) drawn again only when the view moves or the risk or
  // the labels change; the trails and the longest-waiting valves drawn again when a frame
  // comes; the vehicles, moving between frames, every redraw.
  const seabed = document.createElement("canvas");
  const overlay = document.createElement("canvas");
  let seabedKey = "", overlayKey = "";

  function layer(canvasLayer) {
    if (canvasLayer.width !== canvas.width || canvasLayer.height !== canvas.height) {
      canvasLayer.width = canvas.width;
      canvasLayer.height = canvas.height;
    }
    const g = canvasLayer.getContext("2d");
    g.setTransform(1, 0, 0, 1, 0, 0);
    g.clearRect(0, 0, canvasLayer.width, canvasLayer.height);
    g.setTransform(dpr, 0, 0, dpr, 0, 0);
    g.font = "11px system-ui, sans-serif";
    g.textAlign = "center";
    g.textBaseline = "middle";
    return g;
  }

  const valveRadius = (s) => Math.max(3, scene.visit_radius_m * s);

  function drawSeabed(s, labels) {
    const g = layer(seabed);
    g.fillStyle = BACKGROUND;
    g.fillRect(0, 0, width, height);  // opaque: the overlay starts from a copy of it
    g.fillStyle = "#0e2233";
    g.fillRect(sx(0), sy(scene.height_m), scene.width_m * s, scene.height_m * s);
    if (heat && $("heat-mode").value === "risk") {
      g.imageSmoothingEnabled = true;
      g.drawImage(heat.canvas, sx(0), sy(heat.ny * heat.cell_m), heat.nx * heat.cell_m * s, heat.ny * heat.cell_m * s);
    }
    g.strokeStyle = "#2c4a66";
    g.lineWidth = 1;
    g.strokeRect(sx(0), sy(scene.height_m), scene.width_m * s, scene.height_m * s);
    // The seabed's pipes at their width (a pixel and a half at least) and its boulders, in the
    // ochre of the plots, under the structures.
    g.strokeStyle = "#9c7a32";
    g.lineCap = "round";
    g.lineJoin = "round";
    for (const [, diameter, xy] of scene.flowlines || []) {
      g.lineWidth = Math.max(1.5, diameter * s);
      g.beginPath();
      for (let k = 0; k + 1 < xy.length; k += 2) (k ? g.lineTo : g.moveTo).call(g, sx(xy[k]), sy(xy[k + 1]));
      g.stroke();
    }
    g.lineWidth = 1;
    g.fillStyle = "#6b5a3a";
    g.beginPath();
    for (const [bx, by, diameter] of scene.boulders || []) {
      const r = Math.max(1.5, (diameter / 2) * s);
      g.moveTo(sx(bx) + r, sy(by));
      g.arc(sx(bx), sy(by), r, 0, 2 * Math.PI);
    }
    g.fill();
    g.fillStyle = "#4e5a68";
    g.beginPath();
    for (const [, cx, cy, w, h] of scene.structures) g.rect(sx(cx - w / 2), sy(cy + h / 2), w * s, h * s);
    g.fill();
    if (labels && scene.structures.length < 400) {
      g.fillStyle = "#c9d3dc";
      for (const [name, cx, cy, , h] of scene.structures) g.fillText(name, sx(cx), sy(cy + h / 2) - 7);
    }
    if (!frame) return;
    // Valves coloured by their share of the risk against the largest, in 16 steps (a path each).
    let largest = 0;
    for (const v of frame.valves) largest = Math.max(largest, v[1]);
    const radius = valveRadius(s);
    const buckets = Array.from({ length: 16 }, () => []);
    frame.valves.forEach((v, i) => {
      const u = largest > 0 ? v[1] / largest : 0;
      buckets[Math.min(15, Math.floor(u * 16))].push(i);
    });
    buckets.forEach((list, b) => {
      if (!list.length) return;
      g.fillStyle = riskColor((b + 0.5) / 16);
      g.beginPath();
      for (const i of list) {
        const x = sx(scene.valves[i][2]), y = sy(scene.valves[i][3]);
        g.moveTo(x + radius, y);
        g.arc(x, y, radius, 0, 2 * Math.PI);
      }
      g.fill();
    });
    if (labels && scene.valves.length < 1500) {
      g.fillStyle = "#ffffff";
      frame.valves.forEach((v, i) => {
        const wait = v[2] === null ? "never" : `${Math.round(frame.t - v[2])} s`;
        g.fillText(`${scene.valves[i][0]} · ${wait}`, sx(scene.valves[i][2]), sy(scene.valves[i][3]) + radius + 8);
      });
    }
  }

  const WAITING_RINGS = 5;  // the valves that have waited longest, ringed
  function drawOverlay(s) {
    const g = layer(overlay);
    // The seabed under it: a redraw then copies one opaque picture before the vehicles.
    g.setTransform(1, 0, 0, 1, 0, 0);
    g.drawImage(seabed, 0, 0);
    g.setTransform(dpr, 0, 0, dpr, 0, 0);
    const radius = valveRadius(s);
    // Trails: one path for those flying, one for the greyed.
    const status = new Map();
    for (const v of frame.v) status.set(v[0], v[5]);
    // A large fleet's trails with every other point: a thousand full trails were the costliest
    // part of a redraw.
    const step = frame.v.length > 300 ? 4 : 2;
    for (const grey of [false, true]) {
      g.strokeStyle = grey ? "rgba(140,150,160,0.4)" : "rgba(255,180,90,0.75)";
      g.lineWidth = 1;
      g.beginPath();
      for (const [id, { xy }] of trails) {
        if ((status.get(id) !== 0) !== grey || xy.length < 4) continue;
        g.moveTo(sx(xy[0]), sy(xy[1]));
        for (let k = step; k < xy.length; k += step) g.lineTo(sx(xy[k]), sy(xy[k + 1]));
        const n = xy.length;
        if ((n - 2) % step !== 0) g.lineTo(sx(xy[n - 2]), sy(xy[n - 1]));
      }
      g.stroke();
    }
    const waits = [];
    frame.valves.forEach((v, i) => waits.push([v[2] === null ? Infinity : frame.t - v[2], i]));
    waits.sort((a, b) => b[0] - a[0]);
    g.strokeStyle = "#ff9c33";
    g.lineWidth = 2;
    g.setLineDash([4, 3]);
    g.beginPath();
    for (const [, i] of waits.slice(0, WAITING_RINGS)) {
      const x = sx(scene.valves[i][2]), y = sy(scene.valves[i][3]);
      g.moveTo(x + radius + 5, y);
      g.arc(x, y, radius + 5, 0, 2 * Math.PI);
    }
    g.stroke();
    g.setLineDash([]);
    if (selectedValve >= 0) {
      g.strokeStyle = "#ffffff";
      g.beginPath();
      g.arc(sx(scene.valves[selectedValve][2]), sy(scene.valves[selectedValve][3]), radius + 9, 0, 2 * Math.PI);
      g.stroke();
    }
  }

  function draw() {
    const now = performance.now();
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    if (!scene) {
      ctx.fillStyle = BACKGROUND;
      ctx.fillRect(0, 0, canvas.width, canvas.height);
      return;
    }
    const s = scale();
    const labels = s > 12;
    const viewKey = `${canvas.width}x${canvas.height}|${zoom}|${panX}|${panY}`;
    // Labels carry the time since each visit: the seabed again each second while they show.
    const key = `${viewKey}|${frame ? frame.heat_seq : -1}|${heatSeq}|${$("heat-mode").value}|` +
                `${labels && frame ? Math.floor(frame.t) : ""}|${frame ? 1 : 0}`;
    if (key !== seabedKey) {
      drawSeabed(s, labels);
      seabedKey = key;
      overlayKey = "";  // the overlay holds a copy of the seabed
      view.seabedMs = average(view.seabedMs, performance.now() - now);
    }
    if (!frame) {
      ctx.drawImage(seabed, 0, 0);
    } else {
      const okey = `${viewKey}|${view.updates}|${selectedValve}`;
      if (okey !== overlayKey) {
        const t2 = performance.now();
        drawOverlay(s);
        overlayKey = okey;
        view.overlayMs = average(view.overlayMs, performance.now() - t2);
      }
      // One opaque copy a redraw (seabed, trails, rings): with a thousand vehicles in software
      // rendering every full-canvas pass costs the mission's machine.
      const t1 = performance.now();
      ctx.drawImage(overlay, 0, 0);
      view.blitMs = average(view.blitMs, performance.now() - t1);
      ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
      const t3 = performance.now();
      drawVehicles(now, s);
      view.vehiclesMs = average(view.vehiclesMs, performance.now() - t3);
    }
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    drawScaleBar(s);
    view.frames++;
  }

  // Vehicles: a triangle along the heading, at least 6 px; flying ones orange, the others grey.
  function drawVehicles(now, s) {
    const size = Math.max(6, HULL_M * s);
    const paths = [new Path2D(), new Path2D(), new Path2D(), new Path2D()];
    for (const v of frame.v) {
      const p = positions.get(v[0]);
      if (!p) continue;
      const [x, y, h] = v[5] === 0 ? interpolate(p, now) : [p.x1, p.y1, p.h1];
      const X = sx(x), Y = sy(y), c = Math.cos(h), n = Math.sin(h);
      const path = paths[v[5]];
      // Screen y points down: the heading's sine flips.
      path.moveTo(X + c * size, Y - n * size);
      path.lineTo(X - c * size * 0.6 - n * size * 0.55, Y + n * size * 0.6 - c * size * 0.55);
      path.lineTo(X - c * size * 0.6 + n * size * 0.55, Y + n * size * 0.6 + c * size * 0.55);
      path.closePath();
    }
    const fills = ["#ff9c33", "#a9b4bf", "#5d6670", "#7b858f"];
    for (let k = 3; k >= 0; k--) {
      ctx.fillStyle = fills[k];
      ctx.fill(paths[k]);
    }
    if (s > 20 && frame.v.length <= 300) {
      ctx.font = "11px system-ui, sans-serif";
      ctx.textBaseline = "middle";
      ctx.fillStyle = "#ffe2bf";
      ctx.textAlign = "left";
      for (const v of frame.v) {
        const p = positions.get(v[0]);
        if (!p) continue;
        const [x, y] = v[5] === 0 ? interpolate(p, now) : [p.x1, p.y1];
        ctx.fillText(v[5] === 0 ? v[1] : `${v[1]} (${STATUS[v[5]]})`, sx(x) + size + 2, sy(y));
      }
    }
  }

  function drawScaleBar(s) {
    const target = 120 / s;  // metres in about 120 px
    const step = Math.pow(10, Math.floor(Math.log10(target)));
    const metres = [1, 2, 5, 10].map((m) => m * step).filter((m) => m <= target).pop() || step;
    const x = 16, y = height - 18;
    ctx.strokeStyle = "#d7e2ec";
    ctx.lineWidth = 2;
    ctx.beginPath();
    ctx.moveTo(x, y - 4); ctx.lineTo(x, y); ctx.lineTo(x + metres * s, y); ctx.lineTo(x + metres * s, y - 4);
    ctx.stroke();
    ctx.font = "11px system-ui, sans-serif";
    ctx.textBaseline = "middle";
    ctx.fillStyle = "#d7e2ec";
    ctx.textAlign = "left";
    ctx.fillText(`${metres >= 1 ? metres : metres.toFixed(2)} m`, x + metres * s + 6, y - 2);
  }

  // The page's own frame counter: every redraw counts; frames/s over the last second.
  let countFrom = performance.now(), countedFrames = 0, countedUpdates = 0;
  const average = (old, x) => (old === 0 ? x : 0.9 * old + 0.1 * x);
  let lastDraw = 0;
  function loop() {
    const drawStart = performance.now();
    if (drawsOnFrames() && drawStart - lastFrameAt < 2 * frameInterval) {
      // The k-th redraw of a frame at k / DRAWS_PER_FRAME of the interval after it came.
      if (drawsOfFrame < DRAWS_PER_FRAME && drawStart - lastFrameAt >= drawsOfFrame * frameInterval / DRAWS_PER_FRAME - 2) {
        drawsOfFrame++;
        lastDraw = drawStart;
        draw();
        view.drawMs = average(view.drawMs, performance.now() - drawStart);
      }
    } else {
      const interval = 1000 / maxFps();
      if (drawStart - lastDraw >= interval - 2) {
        // On the cap's own schedule: one late animation frame does not push every later redraw.
        lastDraw = drawStart - lastDraw < 2 * interval ? lastDraw + interval : drawStart;
        draw();
        view.drawMs = average(view.drawMs, performance.now() - drawStart);
      }
    }
    const now = performance.now();
    if (now - countFrom >= 1000) {
      view.fps = (view.frames - countedFrames) * 1000 / (now - countFrom);
      view.updateRate = (view.updates - countedUpdates) * 1000 / (now - countFrom);
      countFrom = now;
      countedFrames = view.frames;
      countedUpdates = view.updates;
      $("fps").textContent = view.fps.toFixed(0);
      $("rate").textContent = view.updateRate.toFixed(1);
    }
    if (scene && scene.mode !== "live") advanceReplay(now);
    // On the server's clock the tables too are written just after a frame.
    if (tableDirty && now - lastTable >= TABLE_PERIOD_MS && (!drawsOnFrames() || now - lastFrameAt < frameInterval / 2)) {
      renderTables(now);
      view.tableMs = average(view.tableMs, performance.now() - now);
    }
    next(now);
  }

  // On the server's clock nothing is drawn between the planned redraws, so the page sleeps until
  // the next one (or the next frame, which wakes it) instead of running at every display frame:
  // sixty wake-ups a second of the renderer and compositor beside the mission. Otherwise, and
  // whenever the next redraw is near, the display's own frames.
  let sleeping = null;
  function next(now) {
    if (!drawsOnFrames() || now - lastFrameAt >= 2 * frameInterval) {
      requestAnimationFrame(loop);
      return;
    }
    const due = drawsOfFrame < DRAWS_PER_FRAME ? lastFrameAt + drawsOfFrame * frameInterval / DRAWS_PER_FRAME - 2
                                               : lastFrameAt + 2 * frameInterval;  // the frame wakes it before
    const wait = due - performance.now() - 8;  // woken a little early, drawn on the display frame after
    if (wait <= 0) {
      requestAnimationFrame(loop);
      return;
    }
    sleeping = setTimeout(() => {
      sleeping = null;
      requestAnimationFrame(loop);
    }, Math.min(wait, 250));
  }
  function wake() {
    if (sleeping === null) return;
    clearTimeout(sleeping);
    sleeping = null;
    requestAnimationFrame(loop);
  }

  // ---------- the panel ----------
  function setupScene() {
    document.title = `${scene.mission} — SAGE Fleet`;
    $("mission").textContent = scene.mission;
    $("mode").textContent = scene.mode === "live" ? "live" : "replay";
    $("mode").className = "badge " + scene.mode;
    $("actions").hidden = !scene.actions;
    const names = $("valve-names");
    names.textContent = "";
    for (const v of scene.valves.slice(0, 5000)) {
      const option = document.createElement("option");
      option.value = v[0];
      names.appendChild(option);
    }
    resize();
    drawLegend();
  }

  function drawLegend() {
    const bar = $("legend-bar").getContext("2d");
    for (let i = 0; i < 120; i++) {
      bar.fillStyle = riskColor(i / 119);
      bar.fillRect(i, 0, 1, 10);
    }
  }

  function updateStats() {
    const f = frame;
    $("clock").textContent = `t = ${f.t.toFixed(1)} s`;
    $("clock-of").textContent = `of ${Math.round(f.duration)} s`;
    $("progress").value = f.duration > 0 ? Math.min(1, f.t / f.duration) : 0;
    $("vehicle-count").textContent = f.counts.alive;
    $("stale-count").textContent = f.counts.stale;
    $("lost-count").textContent = f.counts.lost;
    $("left-count").textContent = f.counts.left;
    $("metric").textContent = f.metric === null ? "–" : f.metric.toExponential(2);
    $("cycle").textContent = scene.mode === "live" ? `${f.cycle_ms.toFixed(2)} ms` : "–";
    let largest = 0;
    for (const v of f.valves) largest = Math.max(largest, v[1]);
    $("legend-max").textContent = `0 … ${(100 * largest).toFixed(1)} %`;
    if (scene.mode !== "live" && !sliding) $("slider").value = f.t;
  }

  let lastTable = 0, eventsShown = -1, eventsListed = -1;
  function renderTables(now) {
    lastTable = now;
    tableDirty = false;
    if (!frame) return;
    // The valves: sorted (default: waiting longest first), filtered, the first 100 rows.
    const filter = $("valve-filter").value.trim().toLowerCase();
    const rows = [];
    frame.valves.forEach((v, i) => {
      const [name, xt] = scene.valves[i];
      if (filter && !name.toLowerCase().includes(filter) && !xt.toLowerCase().includes(filter)) return;
      rows.push({ i, name, xt, raw: v[0], share: v[1], visits: v[3], wait: v[2] === null ? frame.t + 1e9 : frame.t - v[2] });
    });
    const key = sortKey;
    rows.sort((a, b) => {
      const d = typeof a[key] === "string" ? a[key].localeCompare(b[key]) : a[key] - b[key];
      return sortUp ? d : -d;
    });
    const never = frame.valves.filter((v) => v[2] === null).length;
    $("valve-summary").textContent = `${frame.valves.length} · ${never} never visited`;
    const body = $("valves").tBodies[0];
    const fragment = document.createDocumentFragment();
    for (const r of rows.slice(0, TABLE_ROWS)) {
      const tr = document.createElement("tr");
      if (r.i === selectedValve) tr.className = "selected";
      const wait = r.wait >= 1e9 ? "never" : `${r.wait.toFixed(0)} s`;
      const cells = [r.name, r.xt, fmt(r.raw), `${(100 * r.share).toFixed(1)} %`, String(r.visits), wait];
      cells.forEach((text, k) => {
        const td = document.createElement("td");
        td.textContent = text;
        if (k >= 2) td.className = "num";
        if (k === 5 && r.wait >= 1e9) td.className = "num overdue";
        tr.appendChild(td);
      });
      tr.addEventListener("click", () => selectValve(r.i));
      fragment.appendChild(tr);
    }
    body.textContent = "";
    body.appendChild(fragment);
    // The log, newest first (written again only when it grew).
    if (eventsSeen === eventsShown && events.length === eventsListed) return;
    eventsShown = eventsSeen;
    eventsListed = events.length;
    const list = $("events");
    const items = document.createDocumentFragment();
    for (let k = events.length - 1; k >= 0 && k >= events.length - 200; k--) {
      const [, t, kind, text] = events[k];
      const li = document.createElement("li");
      li.className = kind;
      const time = document.createElement("span");
      time.className = "t";
      time.textContent = `${t.toFixed(1)} s`;
      li.appendChild(time);
      li.appendChild(document.createTextNode(" " + text));
      items.appendChild(li);
    }
    list.textContent = "";
    list.appendChild(items);
    $("event-count").textContent = `${eventsSeen} in all`;
  }

  function fmt(x) {
    if (x === 0) return "0";
    return Math.abs(x) >= 1000 || Math.abs(x) < 0.01 ? x.toExponential(2) : String(+x.toPrecision(4));
  }

  for (const th of document.querySelectorAll("#valves th")) {
    th.addEventListener("click", () => {
      const key = th.dataset.key;
      if (sortKey === key) sortUp = !sortUp;
      else { sortKey = key; sortUp = key === "name" || key === "xt"; }
      for (const other of document.querySelectorAll("#valves th")) other.classList.remove("sorted", "up");
      th.classList.add("sorted");
      if (sortUp) th.classList.add("up");
      tableDirty = true;
    });
  }
  $("valve-filter").addEventListener("input", () => { tableDirty = true; });

  // ---------- operator actions (live) ----------
  function showAnswer(answer) {
    view.lastAnswer = answer;
    const p = $("answer");
    p.textContent = answer.line;
    p.className = answer.accepted ? "ok" : "err";
  }

  async function act(fields) {
    showAnswer({ accepted: true, line: "…" });
    try {
      const answer = await api("/api/action", {
        method: "POST",
        headers: { "Content-Type": "application/x-www-form-urlencoded" },
        body: new URLSearchParams(fields).toString(),
      });
      showAnswer(answer);
    } catch (e) {
      showAnswer({ accepted: false, line: e.message });
    }
  }

  $("risk-form").addEventListener("submit", (event) => {
    event.preventDefault();
    act({ verb: "risk", valve: $("risk-valve").value.trim(), weight: $("risk-weight").value.trim() });
  });
  $("add-form").addEventListener("submit", (event) => {
    event.preventDefault();
    act({ verb: "add", count: $("add-count").value.trim() });
  });
  $("remove-form").addEventListener("submit", (event) => {
    event.preventDefault();
    act({ verb: "remove", id: $("remove-id").value.trim() });
  });
  $("stop-form").addEventListener("submit", (event) => {
    event.preventDefault();
    if (window.confirm("End the mission now? Its server writes the run directory.")) act({ verb: "stop" });
  });

  // ---------- replay ----------
  let playing = false, replayT = 0, lastTick = 0, fetching = false, wantT = null, sliding = false;
  function startReplay() {
    setLink("recorded", "replay");
    $("replay-controls").hidden = false;
    const slider = $("slider");
    slider.max = scene.replay_end_s;
    slider.addEventListener("input", () => { sliding = true; replayT = +slider.value; wantT = replayT; });
    slider.addEventListener("change", () => { sliding = false; });
    $("play").addEventListener("click", () => {
      playing = !playing;
      if (playing && replayT >= scene.replay_end_s) replayT = 0;
      $("play").textContent = playing ? "❚❚ pause" : "▶ play";
      lastTick = performance.now();
    });
    wantT = 0;
  }
  function advanceReplay(now) {
    if (playing) {
      replayT = Math.min(scene.replay_end_s, replayT + (now - lastTick) / 1000 * +$("speed").value);
      wantT = replayT;
      if (replayT >= scene.replay_end_s) {
        playing = false;
        $("play").textContent = "▶ play";
      }
    }
    lastTick = now;
    if (wantT !== null && !fetching) {
      const t = wantT;
      wantT = null;
      fetching = true;
      api("/api/frame?t=" + t.toFixed(3))
        .then((f) => { takeFrame(f); })
        .catch((e) => setLink(e.message, "down"))
        .finally(() => { fetching = false; });
    }
  }

  resize();
  requestAnimationFrame(loop);
  start();
})();
