// The lumos preview page: draws the frames the server sends and sends it the user's edits (server.py says the
// protocol). No libraries: the page must work with nothing outside this machine reachable.
"use strict";

const $ = (id) => document.getElementById(id);
const token = new URLSearchParams(location.search).get("token") || "";
const SEND_EVERY_MS = 60;        // a dragged slider sends at most this often (the last value always goes)
const ORBIT_DEG_PER_PX = 0.35;   // camera orbit per pixel dragged
const CLICK_SLOP_PX = 4;         // a press that moves less than this is a click (explain), not a drag

// what the tests and the benchmark read (window.lumos)
const probe = { frames: 0, lastFrame: null, latencies: [], explains: 0, errors: [], state: null };
window.lumos = probe;

let socket = null;
let state = null;
let nextId = 1;
const sentAt = new Map();      // message id -> performance.now() when the change was sent
const waiting = [];            // {generation, t0}: changes whose first image has not been drawn yet
let frameMeta = null;          // the JSON half of a frame, waiting for its PNG
let drawing = Promise.resolve();

// ------------------------------------------------------------------------------------------------- socket

function connect() {
  const scheme = location.protocol === "https:" ? "wss" : "ws";
  socket = new WebSocket(`${scheme}://${location.host}/ws?token=${encodeURIComponent(token)}`);
  socket.binaryType = "blob";
  socket.onopen = () => setConnection("connected", "ok");
  socket.onclose = () => setConnection("disconnected: the server stopped (the last image stays)", "lost");
  socket.onmessage = (event) => {
    if (typeof event.data !== "string") {
      const meta = frameMeta;
      frameMeta = null;
      if (meta) drawing = drawing.then(() => drawFrame(meta, event.data)).catch((e) => say(String(e), "error"));
      return;
    }
    let message;
    try { message = JSON.parse(event.data); } catch (e) { return; }
    const handler = handlers[message.type];
    if (handler) handler(message);
  };
}

function send(message, timed = false) {
  if (!socket || socket.readyState !== WebSocket.OPEN) return;
  message.id = nextId++;
  if (timed) sentAt.set(message.id, performance.now());
  socket.send(JSON.stringify(message));
}

function setConnection(text, kind) {
  const el = $("connection");
  el.textContent = text;
  el.className = `connection ${kind}`;
}

const handlers = {
  state: (m) => applyState(m),
  ack: (m) => {
    const t0 = sentAt.get(m.id);
    sentAt.delete(m.id);
    if (t0 !== undefined && m.generation !== undefined) waiting.push({ generation: m.generation, t0 });
  },
  frame: (m) => { frameMeta = m; },
  busy: (m) => {
    const last = probe.lastFrame;
    if (!last || last.generation < m.generation) $("status").textContent = `${m.method} · rendering…`;
  },
  error: (m) => { probe.errors.push(m.message); say(m.message, "error"); sentAt.delete(m.id); },
  note: (m) => say(m.message, "note"),
  explain: (m) => showExplain(m),
  saved: (m) => { $("save-note").textContent = `saved ${m.path}`; say(`saved ${m.path}`, "note"); },
};

// ------------------------------------------------------------------------------------------------- frames

async function drawFrame(meta, blob) {
  const bitmap = await createImageBitmap(blob);
  const canvas = $("image");
  if (meta.stage !== "quick" && (canvas.width !== meta.width || canvas.height !== meta.height)) {
    canvas.width = meta.width;
    canvas.height = meta.height;
  }
  const ctx = canvas.getContext("2d");
  ctx.imageSmoothingEnabled = true;
  ctx.drawImage(bitmap, 0, 0, canvas.width, canvas.height);
  bitmap.close();
  $("placeholder").hidden = true;
  probe.frames += 1;
  probe.lastFrame = meta;
  const now = performance.now();
  for (let i = waiting.length - 1; i >= 0; i--) {
    if (meta.generation >= waiting[i].generation) {
      probe.latencies.push({ generation: waiting[i].generation, ms: now - waiting[i].t0, stage: meta.stage });
      waiting.splice(i, 1);
    }
  }
  $("status").textContent = statusLine(meta);
}

function statusLine(meta) {
  const s = meta.status || {};
  const parts = [s.method + (s.method === "raster" && s.shading ? ` (${s.shading})` : ""), `${meta.width}×${meta.height}`];
  if (meta.stage === "quick") parts.push("quick pass");
  parts.push(`${s.spp ?? "?"}${s.spp_target ? "/" + s.spp_target : ""} spp`);
  if (s.passes) parts.push(`pass ${s.passes}`);
  if (s.elapsed_s !== undefined && s.elapsed_s !== null) parts.push(`${s.elapsed_s.toFixed(2)} s`);
  if (s.mrays_per_s) parts.push(`${s.mrays_per_s.toFixed(2)} Mrays/s`);
  if (s.done) parts.push("done");
  else if (s.eta_s !== undefined && s.eta_s !== null) parts.push(`ETA ${formatSeconds(s.eta_s)}`);
  else parts.push("rendering…");
  if (meta.view && meta.view !== "image") parts.push(`view: ${meta.view}`);
  return parts.join(" · ");
}

function formatSeconds(s) {
  return s < 60 ? `${s.toFixed(1)} s` : `${Math.floor(s / 60)} min ${Math.round(s % 60)} s`;
}

// ------------------------------------------------------------------------------------------------ controls

function applyState(m) {
  const first = state === null;
  state = m;
  probe.state = m;
  $("scene-name").textContent = m.scene;
  document.title = `${m.scene} · lumos preview`;
  document.body.classList.toggle("viewer", !m.editable);
  fillSelect($("method"), m.methods, m.settings.method);
  fillSelect($("shading"), m.shadings, m.settings.shading);
  fillSelect($("tonemap"), m.tonemaps, m.display.tonemap);
  fillSelect($("view"), m.views, m.display.view);
  setIfIdle($("spp"), m.settings.spp);
  for (const id of ["method", "shading", "spp"]) $(id).disabled = !m.editable;
  if (m.editable) $("shading").disabled = m.settings.method !== "raster";
  const stops = Math.log2(m.display.exposure);
  setIfIdle($("exposure"), stops);
  showExposure();
  $("hint").textContent = m.editable ? "drag to orbit · wheel to zoom · click a pixel to explain it"
    : "the image of `lumos render` · click a pixel to explain it";
  if (first && m.editable) {
    buildLights(m.scene_edit.lights);
    buildMaterials(m.scene_edit.materials);
    $("save-name").value = m.scene.replace(/\.(ya?ml|json)$/i, "") + "-edited.yaml";
  }
  const canvas = $("image");
  if (probe.frames === 0 && m.settings.width) { canvas.width = m.settings.width; canvas.height = m.settings.height; }
}

function fillSelect(select, options, value) {
  const same = select.options.length === options.length && [...select.options].every((o, i) => o.value === options[i]);
  if (!same) {
    select.replaceChildren(...options.map((name) => new Option(name, name)));
  }
  if (document.activeElement !== select) select.value = value;
}

function setIfIdle(input, value) {
  if (document.activeElement !== input) input.value = value;
}

function showExposure() {
  const stops = parseFloat($("exposure").value);
  $("exposure-out").textContent = `×${Math.pow(2, stops).toFixed(2)}`;
}

// A control whose changes go out at most every SEND_EVERY_MS, the last one always.
function throttled(sendValue) {
  let timer = null, last = 0, value;
  return (v) => {
    value = v;
    const wait = SEND_EVERY_MS - (performance.now() - last);
    if (timer) return;
    if (wait <= 0) { last = performance.now(); sendValue(value); return; }
    timer = setTimeout(() => { timer = null; last = performance.now(); sendValue(value); }, wait);
  };
}

function slider(parent, label, { min, max, step, value, digits = 2, onValue, id }) {
  const row = document.createElement("div");
  row.className = "row";
  const name = document.createElement("label");
  name.textContent = label;
  const input = document.createElement("input");
  input.type = "range";
  Object.assign(input, { min, max, step, value });
  if (id) { input.id = id; name.htmlFor = id; }
  const out = document.createElement("output");
  out.textContent = Number(value).toFixed(digits);
  const push = throttled(onValue);
  input.addEventListener("input", () => { out.textContent = Number(input.value).toFixed(digits); push(parseFloat(input.value)); });
  row.append(name, input, out);
  parent.append(row);
  return input;
}

function buildLights(lights) {
  const select = $("light");
  if (!lights.length) {
    select.replaceChildren(new Option("(no lights)", ""));
    select.disabled = true;
    return;
  }
  select.replaceChildren(...lights.map((light) => new Option(light.label, String(light.index))));
  const show = () => {
    const light = lights.find((l) => String(l.index) === select.value);
    $("light-swatch").style.background = light.colour;
    const box = $("light-sliders");
    box.replaceChildren();
    const top = Math.max(4 * light.base_strength, 1);
    slider(box, light.strength_key, { min: 0, max: top, step: top / 400, value: light.strength, id: "light-strength",
      onValue: (v) => { light.strength = v; send({ type: "light", index: light.index, key: "strength", value: v }, true); } });
    for (const [key, vector] of Object.entries(light.vectors)) {
      const centre = light.base_vectors[key] || vector;
      const span = key === "direction" ? 1 : light.span;
      ["x", "y", "z"].forEach((axis, k) => {
        slider(box, `${key} ${axis}`, { min: centre[k] - span, max: centre[k] + span, step: span / 200, value: vector[k],
          id: `light-${key}-${axis}`,
          onValue: (v) => { vector[k] = v; send({ type: "light", index: light.index, key, value: [...vector] }, true); } });
      });
    }
  };
  select.addEventListener("change", show);
  show();
}

const MATERIAL_SLIDERS = {
  ka: [0, 1, 0.01], kd: [0, 1, 0.01], ks: [0, 1, 0.01], shininess: [0, 300, 1], kr: [0, 1, 0.01], kt: [0, 1, 0.01],
  ior: [1, 3, 0.01],
};

function buildMaterials(materials) {
  const select = $("material");
  if (!materials.length) {
    select.replaceChildren(new Option("(no named materials)", ""));
    select.disabled = true;
    return;
  }
  const byName = Object.fromEntries(materials.map((m) => [m.name, m]));
  select.replaceChildren(...materials.map((m) => new Option(m.name, m.name)));
  const show = () => {
    const material = byName[select.value];
    $("material-swatch").style.background = material.colour;
    const box = $("material-sliders");
    box.replaceChildren();
    for (const [key, [min, max, step]] of Object.entries(MATERIAL_SLIDERS)) {
      const value = material.values[key];
      slider(box, key, { min, max: Math.max(max, value), step, value, digits: key === "shininess" ? 0 : 2, id: `material-${key}`,
        onValue: (v) => { material.values[key] = v; send({ type: "material", name: material.name, key, value: v }, true); } });
    }
  };
  select.addEventListener("change", show);
  show();
}

// ------------------------------------------------------------------------------------------- canvas input

function canvasPixel(event) {
  const canvas = $("image");
  const rect = canvas.getBoundingClientRect();
  const x = Math.floor((event.clientX - rect.left) / rect.width * canvas.width);
  const y = Math.floor((event.clientY - rect.top) / rect.height * canvas.height);
  return { x: Math.min(Math.max(x, 0), canvas.width - 1), y: Math.min(Math.max(y, 0), canvas.height - 1), rect };
}

function setupCanvas() {
  const canvas = $("image");
  let press = null, yaw = 0, pitch = 0, moved = false;
  const flush = throttled(() => {
    if (yaw === 0 && pitch === 0) return;
    send({ type: "camera", yaw, pitch }, true);
    yaw = 0; pitch = 0;
  });
  canvas.addEventListener("pointerdown", (e) => {
    press = { x: e.clientX, y: e.clientY, lastX: e.clientX, lastY: e.clientY };
    moved = false;
    canvas.setPointerCapture(e.pointerId);
  });
  canvas.addEventListener("pointermove", (e) => {
    if (!press || !state || !state.editable) return;
    if (!moved && Math.hypot(e.clientX - press.x, e.clientY - press.y) < CLICK_SLOP_PX) return;
    moved = true;
    canvas.classList.add("dragging");
    yaw -= (e.clientX - press.lastX) * ORBIT_DEG_PER_PX;
    pitch += (e.clientY - press.lastY) * ORBIT_DEG_PER_PX;
    press.lastX = e.clientX; press.lastY = e.clientY;
    flush();
  });
  canvas.addEventListener("pointerup", (e) => {
    canvas.classList.remove("dragging");
    if (press && !moved) explainAt(e);
    press = null;
  });
  const zoom = throttled((factor) => send({ type: "camera", dolly: factor }, true));
  let dolly = 1;
  canvas.addEventListener("wheel", (e) => {
    if (!state || !state.editable) return;
    e.preventDefault();
    dolly *= Math.exp(Math.max(-100, Math.min(100, e.deltaY)) * 0.002);
    zoom(dolly);
    dolly = 1;
  }, { passive: false });
}

function explainAt(event) {
  const { x, y, rect } = canvasPixel(event);
  const canvas = $("image");
  const marker = $("marker");
  marker.hidden = false;
  marker.style.left = `${(x + 0.5) / canvas.width * rect.width}px`;
  marker.style.top = `${(y + 0.5) / canvas.height * rect.height}px`;
  $("explain-head").textContent = `pixel (${x}, ${y}): asking the renderer…`;
  $("explain-text").textContent = "";
  send({ type: "explain", x, y });
}

function showExplain(m) {
  probe.explains += 1;
  const head = $("explain-head");
  head.replaceChildren();
  const value = document.createElement("span");
  value.className = "value";
  const sw = document.createElement("span");
  sw.className = "swatch";
  const rgb = m.value.map((c) => Math.round(255 * Math.pow(Math.min(Math.max(c, 0), 1), 1 / 2.2)));
  sw.style.background = `rgb(${rgb.join(",")})`;
  value.append(sw, document.createTextNode(`pixel (${m.x}, ${m.y}) · ${m.method}`));
  head.append(value);
  if (m.note) {
    const note = document.createElement("div");
    note.textContent = m.note;
    head.append(note);
  }
  // one block per line, wrapped with a hanging indent under its own depth, so the ray tree keeps its shape
  const text = $("explain-text");
  text.replaceChildren(...m.text.split("\n").map((line) => {
    const div = document.createElement("div");
    const depth = line.length - line.trimStart().length;
    div.style.paddingLeft = `${depth + 2}ch`;
    div.style.textIndent = "-2ch";
    div.textContent = line.trimStart();
    return div;
  }));
}

// --------------------------------------------------------------------------------------------- messages

function say(text, kind) {
  const list = $("messages");
  const item = document.createElement("li");
  item.className = kind;
  item.textContent = text;
  list.prepend(item);
  while (list.children.length > 4) list.lastChild.remove();
  setTimeout(() => item.remove(), kind === "error" ? 12000 : 8000);
}

function setupControls() {
  $("method").addEventListener("change", (e) => send({ type: "settings", method: e.target.value }, true));
  $("shading").addEventListener("change", (e) => send({ type: "settings", shading: e.target.value }, true));
  $("spp").addEventListener("change", (e) => send({ type: "settings", spp: parseInt(e.target.value, 10) }, true));
  const exposure = throttled((stops) => send({ type: "display", exposure: Math.pow(2, stops) }));
  $("exposure").addEventListener("input", (e) => { showExposure(); exposure(parseFloat(e.target.value)); });
  $("tonemap").addEventListener("change", (e) => send({ type: "display", tonemap: e.target.value }));
  $("view").addEventListener("change", (e) => send({ type: "display", view: e.target.value }, true));
  $("camera-reset").addEventListener("click", () => send({ type: "camera", reset: true }, true));
  $("save").addEventListener("click", () => send({ type: "save", name: $("save-name").value }));
}

setupControls();
setupCanvas();
connect();
