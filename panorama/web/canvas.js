// Virtual canvases in the photosphere viewer (seed 004): click to place an image, drag to draw.
//
// Loaded by index.html after its own script; it reads that script's top-level `state`
// (yaw, pitch, roll, fov) and draws on a transparent WebGL layer over the #view canvas.
// Conventions are the library's (panorama/canvas.py, ibr/canvas/plane.py): world frame x right,
// y down, z forward, up = -y; the viewer sits at the origin; the view camera is
// Camera.from_fov(W, H, fov) turned by world_from_view(yaw, pitch, roll); pixel (u, v) has its
// centre at integers, so a pointer at CSS position (X, Y) is pixel (X * dpr - 0.5, Y * dpr - 0.5).
// A canvas: centre, normal (toward the viewer), up, size (scene units), resolution (W, H px);
// right = up x normal, down = -up; canvas pixel x = ((P - c).right / width + 1/2) W - 1/2.
// The store (GET/POST canvas-store.json, images via POST canvas-images/<name>) is a small JSON
// next to the panorama, written by `ibr view PANO --serve` and reloaded on start.
(function () {
  "use strict";
  const params = new URLSearchParams(location.search);
  const view = document.getElementById("view");
  const DIST = 2.0;                 // distance of new canvases from the viewer (scene units)
  const IMAGE_FOV = 40;             // angular width of a placed image, degrees
  const BOARD_FOV = 60;             // angular width of a new drawing board, degrees
  const BOARD_PX = 1024;            // drawing board resolution along its width
  const api = { loaded: false, saving: 0, saves: 0, mode: "look", store: { version: 1, canvases: [] } };
  window.ibrCanvas = api;
  const viewState = () => (typeof state !== "undefined" ? state : { yaw: 0, pitch: 0, roll: 0, fov: 90 });

  // ------------------------------------------------------------------ vectors and the view camera
  const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
  const add = (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
  const mul = (a, s) => [a[0] * s, a[1] * s, a[2] * s];
  const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
  const norm = (a) => { const n = Math.hypot(a[0], a[1], a[2]); return n > 0 ? mul(a, 1 / n) : a; };
  function rotation(yawDeg, pitchDeg, rollDeg) {  // world_from_view = Ry(yaw) Rx(pitch) Rz(roll)
    const r = Math.PI / 180, y = yawDeg * r, p = pitchDeg * r, o = rollDeg * r;
    const Ry = [[Math.cos(y), 0, Math.sin(y)], [0, 1, 0], [-Math.sin(y), 0, Math.cos(y)]];
    const Rx = [[1, 0, 0], [0, Math.cos(p), -Math.sin(p)], [0, Math.sin(p), Math.cos(p)]];
    const Rz = [[Math.cos(o), -Math.sin(o), 0], [Math.sin(o), Math.cos(o), 0], [0, 0, 1]];
    const m = (A, B) => A.map((row) => [0, 1, 2].map((j) => row[0] * B[0][j] + row[1] * B[1][j] + row[2] * B[2][j]));
    return m(m(Ry, Rx), Rz);
  }
  function camera() {
    const s = viewState();
    const w = layer.width, h = layer.height;
    return { R: rotation(s.yaw, s.pitch, s.roll), f: w / (2 * Math.tan(s.fov * Math.PI / 360)), w, h,
             cx: (w - 1) / 2, cy: (h - 1) / 2 };
  }
  function rayOf(cam, u, v) {  // unit world direction through pixel (u, v)
    const c = [(u - cam.cx) / cam.f, (v - cam.cy) / cam.f, 1];
    const R = cam.R;
    return norm([R[0][0] * c[0] + R[0][1] * c[1] + R[0][2] * c[2], R[1][0] * c[0] + R[1][1] * c[1] + R[1][2] * c[2],
                 R[2][0] * c[0] + R[2][1] * c[1] + R[2][2] * c[2]]);
  }
  function frame(e) {  // right, down and the buffer size of a store entry
    const n = norm(e.normal);
    let up = sub(e.up, mul(n, dot(e.up, n)));
    up = norm(up);
    return { n, up, right: cross(up, n), down: mul(up, -1) };
  }
  function resolutionOf(e, tex) {
    if (e.resolution) return e.resolution;
    if (tex && tex.width) return [tex.width, tex.height];
    return [1, 1];
  }
  function pick(u, v) {  // nearest canvas under pixel (u, v): {index, x, y, t} or null
    const cam = camera(), d = rayOf(cam, u, v);
    let best = null;
    api.store.canvases.forEach((e, i) => {
      const f = frame(e), den = dot(d, f.n);
      if (Math.abs(den) < 1e-12) return;
      const t = dot(e.center, f.n) / den;
      if (!(t > 0)) return;
      const rel = sub(mul(d, t), e.center);
      const [W, H] = resolutionOf(e, items[i] && items[i].source);
      const x = (dot(rel, f.right) / e.size[0] + 0.5) * W - 0.5;
      const y = (dot(rel, f.down) / e.size[1] + 0.5) * H - 0.5;
      if (x < -0.5 || x > W - 0.5 || y < -0.5 || y > H - 0.5) return;
      if (!best || t < best.t) best = { index: i, x, y, t };
    });
    return best;
  }
  api.pick = pick;

  // ------------------------------------------------------------------ the WebGL layer
  const layer = document.createElement("canvas");
  layer.id = "canvas-layer";
  layer.style.cssText = "position:fixed;left:0;top:0;width:100vw;height:100vh;pointer-events:none;";
  document.body.appendChild(layer);
  const gl = layer.getContext("webgl", { alpha: true, premultipliedAlpha: true, antialias: true, depth: true,
                                         preserveDrawingBuffer: true });
  const vs = `attribute vec4 p; attribute vec2 t; varying vec2 vt; void main() { vt = t; gl_Position = p; }`;
  const fs = `precision highp float; uniform sampler2D img; varying vec2 vt;
              void main() { gl_FragColor = texture2D(img, vt); }`;
  function shader(type, src) {
    const s = gl.createShader(type); gl.shaderSource(s, src); gl.compileShader(s);
    if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(s));
    return s;
  }
  const prog = gl.createProgram();
  gl.attachShader(prog, shader(gl.VERTEX_SHADER, vs));
  gl.attachShader(prog, shader(gl.FRAGMENT_SHADER, fs));
  gl.linkProgram(prog);
  const locP = gl.getAttribLocation(prog, "p"), locT = gl.getAttribLocation(prog, "t");
  const vbuf = gl.createBuffer(), tbuf = gl.createBuffer();
  gl.bindBuffer(gl.ARRAY_BUFFER, tbuf);
  gl.bufferData(gl.ARRAY_BUFFER, new Float32Array([0, 0, 1, 0, 1, 1, 0, 0, 1, 1, 0, 1]), gl.STATIC_DRAW);

  const items = [];  // per store entry: {source (image or 2D canvas), tex, dirty}
  function makeTexture(source) {
    const tex = gl.createTexture();
    gl.bindTexture(gl.TEXTURE_2D, tex);
    gl.pixelStorei(gl.UNPACK_PREMULTIPLY_ALPHA_WEBGL, true);
    gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA, gl.RGBA, gl.UNSIGNED_BYTE, source);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.LINEAR);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.LINEAR);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_S, gl.CLAMP_TO_EDGE);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_T, gl.CLAMP_TO_EDGE);
    return tex;
  }
  function cssColor(c) {
    if (typeof c === "string") return c;
    const v = c.map((x) => Math.round(x * 255));
    return `rgba(${v[0]},${v[1]},${v[2]},${c.length > 3 ? c[3] : 1})`;
  }
  function paintBoard(e, board) {  // strokes in canvas pixels; canvas-2D coordinate = pixel + 1/2
    const ctx = board.getContext("2d");
    ctx.clearRect(0, 0, board.width, board.height);
    if (e.background) { ctx.fillStyle = cssColor(e.background); ctx.fillRect(0, 0, board.width, board.height); }
    ctx.lineCap = "round"; ctx.lineJoin = "round";
    for (const s of e.strokes || []) {
      ctx.strokeStyle = ctx.fillStyle = cssColor(s.color || "#ff3030");
      const w = s.width || 4, pts = s.points;
      if (pts.length === 1) {
        ctx.beginPath(); ctx.arc(pts[0][0] + 0.5, pts[0][1] + 0.5, w / 2, 0, 2 * Math.PI); ctx.fill();
        continue;
      }
      ctx.lineWidth = w;
      ctx.beginPath();
      pts.forEach((p, k) => (k ? ctx.lineTo(p[0] + 0.5, p[1] + 0.5) : ctx.moveTo(p[0] + 0.5, p[1] + 0.5)));
      ctx.stroke();
    }
  }
  function buildItem(e) {
    return new Promise((resolve) => {
      if (e.kind === "image") {
        const img = new Image();
        img.onload = () => resolve({ source: img, tex: makeTexture(img) });
        img.onerror = () => { status("cannot load " + e.image); resolve({ source: null, tex: null }); };
        img.src = "canvas-files/" + e.image.split("/").map(encodeURIComponent).join("/");
      } else {
        const board = document.createElement("canvas");
        [board.width, board.height] = e.resolution;
        paintBoard(e, board);
        resolve({ source: board, tex: makeTexture(board) });
      }
    });
  }
  function refresh(i) {  // a board whose strokes changed
    const it = items[i], e = api.store.canvases[i];
    paintBoard(e, it.source);
    gl.bindTexture(gl.TEXTURE_2D, it.tex);
    gl.pixelStorei(gl.UNPACK_PREMULTIPLY_ALPHA_WEBGL, true);
    gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA, gl.RGBA, gl.UNSIGNED_BYTE, it.source);
    dirty = true;
  }

  let dirty = true, last = "";
  function render() {
    const dpr = window.devicePixelRatio || 1;
    const w = Math.round(view.clientWidth * dpr), h = Math.round(view.clientHeight * dpr);
    if (layer.width !== w || layer.height !== h) { layer.width = w; layer.height = h; dirty = true; }
    const s = viewState(), key = [s.yaw, s.pitch, s.roll, s.fov, w, h].join(",");
    if (!dirty && key === last) return;
    dirty = false; last = key;
    gl.viewport(0, 0, w, h);
    gl.clearColor(0, 0, 0, 0);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.useProgram(prog);
    gl.enable(gl.DEPTH_TEST);
    gl.enable(gl.BLEND);
    gl.blendFunc(gl.ONE, gl.ONE_MINUS_SRC_ALPHA);  // premultiplied "over"
    const cam = camera(), R = cam.R, near = 1e-3, far = 1e4;
    // camera-frame point -> clip: x_ndc = (2f/W) x/z, y_ndc = -(2f/H) y/z (pixel centres at integers
    // with cx = (W - 1)/2 put the image edges at NDC -1 and +1)
    const toClip = (P) => {
      const x = R[0][0] * P[0] + R[1][0] * P[1] + R[2][0] * P[2];
      const y = R[0][1] * P[0] + R[1][1] * P[1] + R[2][1] * P[2];
      const z = R[0][2] * P[0] + R[1][2] * P[1] + R[2][2] * P[2];
      return [2 * cam.f / w * x, -2 * cam.f / h * y, (z * (far + near) - 2 * far * near) / (far - near), z];
    };
    api.store.canvases.forEach((e, i) => {
      const it = items[i];
      if (!it || !it.tex) return;
      const f = frame(e), hw = mul(f.right, e.size[0] / 2), hh = mul(f.down, e.size[1] / 2);
      const tl = sub(sub(e.center, hw), hh), tr = sub(add(e.center, hw), hh);
      const br = add(add(e.center, hw), hh), bl = add(sub(e.center, hw), hh);
      const q = [tl, tr, br, tl, br, bl].map(toClip).flat();
      gl.bindBuffer(gl.ARRAY_BUFFER, vbuf);
      gl.bufferData(gl.ARRAY_BUFFER, new Float32Array(q), gl.DYNAMIC_DRAW);
      gl.enableVertexAttribArray(locP);
      gl.vertexAttribPointer(locP, 4, gl.FLOAT, false, 0, 0);
      gl.bindBuffer(gl.ARRAY_BUFFER, tbuf);
      gl.enableVertexAttribArray(locT);
      gl.vertexAttribPointer(locT, 2, gl.FLOAT, false, 0, 0);
      gl.bindTexture(gl.TEXTURE_2D, it.tex);
      gl.drawArrays(gl.TRIANGLES, 0, 6);
    });
  }
  (function loop() { render(); requestAnimationFrame(loop); })();

  // ------------------------------------------------------------------ the store
  function status(text) { bar.title = text; msg.textContent = text; }
  async function save() {
    api.saving++;
    try {
      const r = await fetch("canvas-store.json", { method: "POST", headers: { "Content-Type": "application/json" },
                                                     body: JSON.stringify(api.store) });
      const body = await r.json();
      if (!r.ok) throw new Error(body.error || r.statusText);
      api.saves++;
      status(`saved ${api.store.canvases.length} canvas(es)`);
    } catch (err) {
      status("not saved: " + err.message);
    } finally {
      api.saving--;
    }
  }
  async function load() {
    try {
      const r = await fetch("canvas-store.json", { cache: "no-store" });
      if (r.ok) api.store = await r.json();
    } catch (err) {
      status("no canvas store: " + err.message);
    }
    for (const e of api.store.canvases) items.push(await buildItem(e));
    dirty = true;
    api.loaded = true;
  }
  api.ready = load();

  function facing(d, widthDeg, aspect) {  // geometry of a canvas facing the viewer along d
    let up = [0, -1, 0];
    if (Math.abs(dot(up, d)) > 0.999) up = rayOf(camera(), camera().cx, camera().cy - 1);  // looking straight up/down
    up = norm(sub(up, mul(d, dot(up, d))));
    const w = 2 * DIST * Math.tan(widthDeg * Math.PI / 360);
    return { center: mul(d, DIST), normal: mul(d, -1), up, size: [w, w * aspect] };
  }

  // ------------------------------------------------------------------ placing an image
  let pending = null;  // {name, width, height} of an uploaded image waiting for a click
  async function upload(file) {
    const base = (file.name.replace(/\.[^.]*$/, "").replace(/[^A-Za-z0-9_-]/g, "_") || "image").slice(0, 40);
    const ext = /png$/i.test(file.type) || /\.png$/i.test(file.name) ? "png" : "jpg";
    const name = `${base}-${Date.now().toString(36)}.${ext}`;
    const r = await fetch("canvas-images/" + name, { method: "POST", body: await file.arrayBuffer() });
    const body = await r.json();
    if (!r.ok) throw new Error(body.error || r.statusText);
    pending = body;
    setMode("image");
    status(`click where ${file.name} goes`);
  }
  async function placeImage(u, v) {
    if (!pending) { status("choose an image first"); return; }
    const d = rayOf(camera(), u, v);
    const e = Object.assign({ kind: "image", image: pending.image }, facing(d, IMAGE_FOV, pending.height / pending.width));
    e.resolution = [pending.width, pending.height];
    api.store.canvases.push(e);
    items.push(await buildItem(e));
    dirty = true;
    pending = null;
    setMode("look");
    await save();
  }

  // ------------------------------------------------------------------ drawing
  let stroke = null;  // {index, points}
  function startStroke(u, v) {
    let hit = pick(u, v);
    if (!hit || api.store.canvases[hit.index].kind !== "strokes") {
      // a new transparent board: in front of the image that was hit, or facing the viewer
      let e;
      if (hit) {
        const img = api.store.canvases[hit.index], f = frame(img);
        const res = resolutionOf(img, items[hit.index].source);
        const k = Math.min(1, BOARD_PX / res[0]);
        e = { kind: "strokes", center: add(img.center, mul(f.n, 1e-3 * DIST)), normal: f.n, up: f.up,
              size: img.size.slice(), resolution: [Math.max(1, Math.round(res[0] * k)), Math.max(1, Math.round(res[1] * k))] };
      } else {
        const cam = camera();
        const g = facing(rayOf(cam, u, v), BOARD_FOV, cam.h / cam.w);
        e = Object.assign({ kind: "strokes" }, g, { resolution: [BOARD_PX, Math.max(1, Math.round(BOARD_PX * cam.h / cam.w))] });
      }
      e.strokes = [];
      api.store.canvases.push(e);
      const board = document.createElement("canvas");
      [board.width, board.height] = e.resolution;
      items.push({ source: board, tex: makeTexture(board) });
      hit = pick(u, v);
      if (!hit) return;
    }
    const e = api.store.canvases[hit.index];
    stroke = { index: hit.index, entry: { points: [[hit.x, hit.y]], width: parseFloat(widthIn.value) || 4,
                                          color: colorIn.value } };
    e.strokes.push(stroke.entry);
    refresh(hit.index);
  }
  function moveStroke(u, v) {
    const hit = pick(u, v);
    if (!stroke || !hit || hit.index !== stroke.index) return;  // off the board: skipped
    stroke.entry.points.push([hit.x, hit.y]);
    refresh(stroke.index);
  }
  async function endStroke() {
    if (!stroke) return;
    stroke = null;
    await save();
  }

  // ------------------------------------------------------------------ toolbar and pointer
  const bar = document.createElement("div");
  bar.id = "canvas-tools";
  bar.style.cssText = "position:fixed;left:8px;top:8px;font:12px sans-serif;color:#ddd;background:rgba(0,0,0,.55);" +
                      "padding:4px 6px;border-radius:4px;user-select:none;";
  bar.innerHTML = `<button data-mode="look">look</button> <button id="canvas-image-btn">image…</button>
    <button data-mode="draw">draw</button> <input id="canvas-color" type="color" value="#ff3030">
    <input id="canvas-width" type="number" value="6" min="1" max="64" style="width:3em">
    <input id="canvas-file" type="file" accept="image/png,image/jpeg" style="display:none">
    <span id="canvas-msg"></span>`;
  document.body.appendChild(bar);
  if (params.get("hud") === "0") bar.style.display = "none";
  const msg = bar.querySelector("#canvas-msg"), fileIn = bar.querySelector("#canvas-file");
  const colorIn = bar.querySelector("#canvas-color"), widthIn = bar.querySelector("#canvas-width");
  bar.querySelectorAll("[data-mode]").forEach((b) => b.addEventListener("click", () => setMode(b.dataset.mode)));
  bar.querySelector("#canvas-image-btn").addEventListener("click", () => fileIn.click());
  fileIn.addEventListener("change", () => {
    if (fileIn.files.length) upload(fileIn.files[0]).catch((err) => status("upload failed: " + err.message));
  });
  function setMode(m) {
    api.mode = m;
    layer.style.pointerEvents = m === "look" ? "none" : "auto";  // look: the viewer's drag turns the view
    layer.style.cursor = m === "draw" ? "crosshair" : m === "image" ? "copy" : "default";
    bar.querySelectorAll("[data-mode]").forEach((b) => { b.style.fontWeight = b.dataset.mode === m ? "bold" : ""; });
  }
  api.setMode = setMode;
  setMode("look");
  const pixel = (e) => { const dpr = window.devicePixelRatio || 1; return [e.clientX * dpr - 0.5, e.clientY * dpr - 0.5]; };
  let down = null;
  layer.addEventListener("pointerdown", (e) => {
    layer.setPointerCapture(e.pointerId);
    down = pixel(e);
    if (api.mode === "draw") startStroke(...down);
  });
  layer.addEventListener("pointermove", (e) => { if (down && api.mode === "draw") moveStroke(...pixel(e)); });
  layer.addEventListener("pointerup", (e) => {
    const p = pixel(e);
    if (api.mode === "draw") endStroke();
    else if (api.mode === "image" && down && Math.hypot(p[0] - down[0], p[1] - down[1]) < 5) placeImage(...p);
    down = null;
  });
})();
