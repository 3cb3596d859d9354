// vcar's web page: a Spark (three.js) splat viewer, vcar in a Web Worker, click (or shift-drag a
// box) to select; alt-click marks several objects and "segment objects" runs them together.
// Unattended contract (docs/web.md):
// index.html?scene=URL&cameras=URL&view=NAME&click=u,v&box=x0,y0,x1,y1&segmenter=grabcut|region
// (click, box or both) runs the whole flow and writes {"selected": n, "seconds": t, "indices":
// [...], "split": {...}} into #vcar-result; objects=u,v;u,v;... (a click per object) runs
// vcar::segment_objects and writes {"objects": [{"selected": n, "indices": [...]}, ...], "seconds": t};
// without a prompt, once the scene is loaded and shown: {"gaussians": n, "format", "viewer": "ok" | why not}.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { SparkRenderer, SplatMesh } from '@sparkjsdev/spark';

const $ = (id) => document.getElementById(id);
const params = new URLSearchParams(location.search);
const status = (s) => { $('status').textContent = s; };

// ---- the worker: one request at a time -----------------------------------------------------
const worker = new Worker('worker.js');
let pending = null;
let workerReady;
const readyPromise = new Promise((r) => { workerReady = r; });
worker.onmessage = (ev) => {
  const m = ev.data;
  if (m.type === 'ready') { workerReady(m); return; }
  if (m.type === 'progress') { onProgress(m); return; }
  const p = pending;
  pending = null;
  if (!p) return;
  if (m.type === 'error') p.reject(new Error(m.message));
  else p.resolve(m);
};
worker.onerror = (e) => { if (pending) { pending.reject(new Error(e.message)); pending = null; } };
function call(msg, transfer = []) {
  if (pending) return Promise.reject(new Error('vcar is busy'));
  return new Promise((resolve, reject) => { pending = { resolve, reject }; worker.postMessage(msg, transfer); });
}

function onProgress(p) {
  const frac = { 'coarse': 0, 'view_completeness': 0.45, 'sss': 0.47, 'abr': 0.96, 'done': 1 };
  let f = frac[p.stage] ?? 0;
  if (p.stage === 'coarse round') f = 0.45 * p.view / p.views;
  if (p.stage === 'fine round') f = 0.47 + 0.49 * p.view / p.views;
  $('progress').value = f;
  status(`${p.stage}${p.views ? ` ${p.view}/${p.views}` : ''} (${p.elapsed.toFixed(1)} s)`);
}

// ---- the viewer (WebGL; the flow runs without it where WebGL is missing) --------------------
const canvas = $('canvas');
let renderer = null, camera = null, controls = null, world = null, mesh = null, original = null;
try {
  renderer = new THREE.WebGLRenderer({ canvas, antialias: false, preserveDrawingBuffer: true });
  world = new THREE.Scene();
  camera = new THREE.PerspectiveCamera(50, 4 / 3, 0.01, 1000);
  world.add(new SparkRenderer({ renderer }));
  controls = new OrbitControls(camera, canvas);
  renderer.setAnimationLoop(() => { controls.update(); renderer.render(world, camera); });
} catch (e) {
  renderer = null;
  status('no WebGL: the viewer is off, vcar still runs (' + e.message + ')');
}

function fitCanvas(aspect) {
  const box = $('viewer').getBoundingClientRect();
  let w = box.width, h = box.width / aspect;
  if (h > box.height) { h = box.height; w = h * aspect; }
  w = Math.floor(w); h = Math.floor(h);
  canvas.style.width = w + 'px'; canvas.style.height = h + 'px';
  if (renderer) renderer.setSize(w, h, false);
  if (camera) { camera.aspect = w / h; camera.updateProjectionMatrix(); }
}

// vcar cameras are OpenCV (x right, y down, z forward; R, t world-to-camera); three's camera
// looks down -z with y up: right = R row 0, up = -R row 1, backward = -R row 2.
function setViewerCamera(c) {
  fitCanvas(c.width / c.height);
  if (!camera) return;
  const row = (i) => new THREE.Vector3(c.R[3 * i], c.R[3 * i + 1], c.R[3 * i + 2]);
  const right = row(0), up = row(1).negate(), back = row(2).negate();
  const t = new THREE.Vector3(c.t[0], c.t[1], c.t[2]);
  const pos = new THREE.Vector3(
    -(c.R[0] * t.x + c.R[3] * t.y + c.R[6] * t.z),
    -(c.R[1] * t.x + c.R[4] * t.y + c.R[7] * t.z),
    -(c.R[2] * t.x + c.R[5] * t.y + c.R[8] * t.z));
  camera.position.copy(pos);
  camera.quaternion.setFromRotationMatrix(new THREE.Matrix4().makeBasis(right, up, back));
  camera.up.copy(up);
  camera.fov = 2 * Math.atan(0.5 * c.height / c.fy) * 180 / Math.PI;
  camera.updateProjectionMatrix();
  let d = 1;
  if (mesh) {
    const centre = mesh.getBoundingBox(true).getCenter(new THREE.Vector3());
    d = Math.max(1e-3, centre.clone().sub(pos).dot(back.clone().negate()));
  }
  controls.target.copy(pos.clone().addScaledVector(back, -d));
  controls.update();
  camera.quaternion.setFromRotationMatrix(new THREE.Matrix4().makeBasis(right, up, back));
}

// The viewer's current camera as a vcar camera of the canvas' CSS size.
function viewerCameraToVcar() {
  const w = canvas.clientWidth, h = canvas.clientHeight;
  const fy = 0.5 * h / Math.tan(0.5 * camera.fov * Math.PI / 180);
  camera.updateMatrixWorld();
  const e = camera.matrixWorld.elements;  // column-major: columns right, up, back, position
  const right = [e[0], e[1], e[2]], down = [-e[4], -e[5], -e[6]], fwd = [-e[8], -e[9], -e[10]];
  const R = [...right, ...down, ...fwd];
  const p = [e[12], e[13], e[14]];
  const t = [0, 1, 2].map((i) => -(R[3 * i] * p[0] + R[3 * i + 1] * p[1] + R[3 * i + 2] * p[2]));
  return { name: 'viewer', width: w, height: h, fx: fy, fy, cx: w / 2, cy: h / 2, R, t };
}

async function showScene(bytes, name) {
  if (!renderer) return;
  if (mesh) { world.remove(mesh); mesh.dispose(); mesh = null; original = null; }
  mesh = new SplatMesh({ fileBytes: bytes, fileName: name });
  world.add(mesh);
  await mesh.initialized;
  if (mesh.packedSplats && mesh.packedSplats.packedArray)
    original = mesh.packedSplats.packedArray.slice();
}

// ---- selection display: highlight, delete, isolate (Spark's packed RGBA8 in word 0) ---------
let selection = null;
function display(mode) {
  if (!mesh || !original || !selection) return;
  const arr = mesh.packedSplats.packedArray;
  arr.set(original);
  const n = mesh.packedSplats.numSplats;
  const sel = new Uint8Array(n);
  for (const i of selection) if (i < n) sel[i] = 1;
  for (let i = 0; i < n; ++i) {
    const w = arr[4 * i];
    let r = w & 255, g = (w >>> 8) & 255, b = (w >>> 16) & 255, a = w >>> 24;
    if (mode === 'highlight' && sel[i]) { r = r >> 2; g = (g + 255) >> 1; b = (b + 160) >> 1; }  // towards green-cyan
    if ((mode === 'delete' && sel[i]) || (mode === 'isolate' && !sel[i])) a = 0;
    arr[4 * i] = (r | (g << 8) | (b << 16) | (a << 24)) >>> 0;
  }
  mesh.packedSplats.needsUpdate = true;
  if (mesh.updateVersion) mesh.updateVersion();
}

// ---- the flow ---------------------------------------------------------------------------------
let sceneName = 'scene.ply';
async function loadScene(bytes, name) {
  sceneName = name;
  status('reading ' + name + '...');
  const viewerCopy = bytes.slice();
  const r = await call({ type: 'scene', bytes: bytes.buffer, name }, [bytes.buffer]);
  status(`${r.n.toLocaleString()} Gaussians (${r.format})`);
  let viewer = 'ok';  // or how Spark showed it, or why it could not
  try { await showScene(viewerCopy, name); } catch (e) {
    // A file Spark does not read (SPZ v4: Spark 2.2 expects gzip) but vcar does: the viewer gets
    // vcar's PLY of the scene (same Gaussians, same order).
    const why = String(e?.message ?? e);
    try {
      await showScene(new Uint8Array((await call({ type: 'ply', kind: 'scene' })).bytes), 'scene.ply');
      viewer = `ok, as vcar's PLY (Spark: ${why})`;
    } catch (e2) { viewer = why; status('viewer: ' + why); }
  }
  selection = null;
  enableResultButtons(false);
  return { ...r, viewer };
}
async function loadCameras(bytes, name) {
  const r = await call({ type: 'cameras', bytes: bytes ? bytes.buffer : null, name }, bytes ? [bytes.buffer] : []);
  const sel = $('view-select');
  sel.innerHTML = '<option value="">(default)</option>' + r.names.map((n) => `<option>${n}</option>`).join('');
  return r;
}
async function referenceView(name) { return (await call({ type: 'view', name })).camera; }

// u, v: the click (NaN: none); options.box: [x0, y0, x1, y1] (pixels of cam), with or instead of
// the click; options.segmenterName, options.quality: the page's choices unless given.
async function segment(cam, u, v, options = {}) {
  const rect = canvas.getBoundingClientRect(), vrect = $('viewer').getBoundingClientRect();
  const sx = rect.width / cam.width, sy = rect.height / cam.height;
  const marker = $('marker');
  marker.hidden = !(Number.isFinite(u) && Number.isFinite(v));
  if (!marker.hidden) {
    marker.style.left = (rect.left - vrect.left + u * sx) + 'px';
    marker.style.top = (rect.top - vrect.top + v * sy) + 'px';
  }
  const frame = $('box');
  frame.hidden = !options.box;
  if (options.box) {
    const [x0, y0, x1, y1] = options.box;
    Object.assign(frame.style, { left: (rect.left - vrect.left + x0 * sx) + 'px', top: (rect.top - vrect.top + y0 * sy) + 'px',
                                 width: ((x1 - x0) * sx) + 'px', height: ((y1 - y0) * sy) + 'px' });
  }
  options = { segmenterName: $('segmenter-select').value, quality: $('quality-select').value, ...options };
  $('progress').value = 0;
  const r = await call({ type: 'segment', camera: cam, u, v, options });
  selection = r.indices;
  display('highlight');
  enableResultButtons(true);
  const d = r.diagnostics;
  status(`selected ${r.indices.length.toLocaleString()} Gaussians in ${r.seconds.toFixed(2)} s`);
  $('details').textContent = JSON.stringify({ simd: simdPath, ...d }, null, 1);
  return r;
}

// Several objects at once (vcar::segment_objects): prompts = [{click: [u, v]} | {box: [...]}]
// on cam. The viewer highlights them all; the downloads stay with single selections.
async function segmentObjects(cam, prompts, options = {}) {
  options = { segmenterName: $('segmenter-select').value, quality: $('quality-select').value, ...options };
  $('progress').value = 0;
  const r = await call({ type: 'segment-objects', camera: cam, prompts, options });
  selection = r.objects.flatMap((o) => Array.from(o.indices));
  display('highlight');
  enableResultButtons(false);
  for (const id of ['btn-delete', 'btn-isolate', 'btn-show']) $(id).disabled = false;
  status(`${r.objects.length} objects: ${r.objects.map((o) => o.indices.length.toLocaleString()).join(' + ')} Gaussians in ${r.seconds.toFixed(2)} s`);
  $('details').textContent = JSON.stringify({ simd: simdPath, objects: r.objects.map((o) => o.diagnostics) }, null, 1);
  return r;
}

function enableResultButtons(on) {
  for (const id of ['btn-delete', 'btn-isolate', 'btn-show', 'dl-object', 'dl-removed', 'dl-state']) $(id).disabled = !on;
}
async function download(kind) {
  const r = await call({ type: 'ply', kind });
  const stem = sceneName.replace(/\.[^.]*$/, '');
  const name = kind === 'object' ? 'object.ply' : kind === 'removed' ? 'removed.ply' : `${stem}.state.ply`;
  const a = document.createElement('a');
  a.href = URL.createObjectURL(new Blob([r.bytes], { type: 'application/octet-stream' }));
  a.download = name;
  a.click();
  setTimeout(() => URL.revokeObjectURL(a.href), 10000);
}

$('btn-delete').onclick = () => display('delete');
$('btn-isolate').onclick = () => display('isolate');
$('btn-show').onclick = () => display('highlight');
$('dl-object').onclick = () => download('object');
$('dl-removed').onclick = () => download('removed');
$('dl-state').onclick = () => download('state');
$('scene-file').onchange = async (e) => {
  const f = e.target.files[0];
  if (!f) return;
  try {
    await loadScene(new Uint8Array(await f.arrayBuffer()), f.name);
    setViewerCamera(await referenceView($('view-select').value));
  } catch (err) { status('error: ' + err.message); }
};
$('cameras-file').onchange = async (e) => {
  const f = e.target.files[0];
  if (!f) return;
  try { await loadCameras(new Uint8Array(await f.arrayBuffer()), f.name); } catch (err) { status('error: ' + err.message); }
};
$('view-select').onchange = async () => {
  try { setViewerCamera(await referenceView($('view-select').value)); } catch (err) { status('error: ' + err.message); }
};

// Click (not drag) on the canvas, or shift-drag a box: segment from the viewer's current camera.
// Alt-click marks an object (from the same camera: do not move the viewer in between).
let down = null, boxing = false, marked = [];
$('btn-objects').onclick = async () => {
  const prompts = marked;
  marked = [];
  $('btn-objects').disabled = true;
  $('btn-objects').textContent = 'segment objects';
  try { await segmentObjects(viewerCameraToVcar(), prompts); } catch (err) { status('error: ' + err.message); }
};
canvas.addEventListener('pointerdown', (e) => {
  down = [e.offsetX, e.offsetY];
  boxing = e.shiftKey && !!camera;
  if (boxing) { controls.enabled = false; canvas.setPointerCapture(e.pointerId); }
}, { capture: true });
canvas.addEventListener('pointermove', (e) => {
  if (!boxing || !down) return;
  const rect = canvas.getBoundingClientRect(), vrect = $('viewer').getBoundingClientRect(), f = $('box');
  f.hidden = false;
  Object.assign(f.style, { left: (rect.left - vrect.left + Math.min(down[0], e.offsetX)) + 'px',
                           top: (rect.top - vrect.top + Math.min(down[1], e.offsetY)) + 'px',
                           width: Math.abs(e.offsetX - down[0]) + 'px', height: Math.abs(e.offsetY - down[1]) + 'px' });
});
canvas.addEventListener('pointerup', async (e) => {
  if (!down || !camera) return;
  const [x, y] = down, wasBoxing = boxing;
  down = null;
  boxing = false;
  if (controls) controls.enabled = true;
  try {
    if (wasBoxing && Math.abs(e.offsetX - x) > 4 && Math.abs(e.offsetY - y) > 4) {
      const box = [Math.min(x, e.offsetX), Math.min(y, e.offsetY), Math.max(x, e.offsetX), Math.max(y, e.offsetY)];
      await segment(viewerCameraToVcar(), NaN, NaN, { box });
    } else if (!wasBoxing && Math.hypot(e.offsetX - x, e.offsetY - y) <= 4 && e.altKey) {
      marked.push({ click: [e.offsetX, e.offsetY] });  // one more object for "segment objects"
      $('btn-objects').disabled = false;
      $('btn-objects').textContent = `segment ${marked.length} object${marked.length > 1 ? 's' : ''}`;
    } else if (!wasBoxing && Math.hypot(e.offsetX - x, e.offsetY - y) <= 4) {
      await segment(viewerCameraToVcar(), e.offsetX, e.offsetY);
    }
  } catch (err) { status('error: ' + err.message); }
});

// For tests and scripting: the worker protocol (docs/web.md) and the current selection.
window.vcarPage = { call, display, segment, segmentObjects, selection: () => selection };

let simdPath = '';
async function unattended() {
  const t0 = performance.now();
  const fetchBytes = async (url) => {
    const r = await fetch(url);
    if (!r.ok) throw new Error(`${url}: HTTP ${r.status}`);
    return new Uint8Array(await r.arrayBuffer());
  };
  const sceneUrl = params.get('scene');
  const loaded = await loadScene(await fetchBytes(sceneUrl), sceneUrl.split('/').pop().split('?')[0]);
  if (params.get('cameras')) {
    const u = params.get('cameras');
    await loadCameras(await fetchBytes(u), u.split('/').pop().split('?')[0]);
  }
  const cam = await referenceView(params.get('view') || '');
  $('view-select').value = params.get('view') || '';
  setViewerCamera(cam);
  const click = params.get('click'), box = params.get('box'), objects = params.get('objects');
  if (objects) {
    const prompts = objects.split(';').map((c) => ({ click: c.split(',').map(Number) }));
    const opts = {};
    if (params.get('segmenter')) opts.segmenterName = params.get('segmenter');
    if (params.get('quality')) opts.quality = params.get('quality');
    if (params.get('maxSide')) opts.maxSide = Number(params.get('maxSide'));
    const r = await segmentObjects(cam, prompts, opts);
    $('vcar-result').textContent = JSON.stringify({
      objects: r.objects.map((o) => ({ selected: o.indices.length, indices: Array.from(o.indices) })),
      seconds: r.seconds, simd: simdPath, page_seconds: (performance.now() - t0) / 1000,
    });
    return;
  }
  if (!click && !box) {  // no prompt: what was loaded
    $('vcar-result').textContent = JSON.stringify({ gaussians: loaded.n, format: loaded.format, viewer: loaded.viewer,
                                                    page_seconds: (performance.now() - t0) / 1000 });
    return;
  }
  const [u, v] = click ? click.split(',').map(Number) : [NaN, NaN];
  const opts = {};
  if (box) opts.box = box.split(',').map(Number);
  if (params.get('segmenter')) opts.segmenterName = params.get('segmenter');
  if (params.get('quality')) opts.quality = params.get('quality');
  if (params.get('maxSide')) opts.maxSide = Number(params.get('maxSide'));
  const r = await segment(cam, u, v, opts);
  await new Promise((res) => requestAnimationFrame(() => requestAnimationFrame(res)));  // the highlight is drawn
  $('vcar-result').textContent = JSON.stringify({
    selected: r.indices.length, seconds: r.seconds, indices: Array.from(r.indices),
    split: { ...r.diagnostics.split, load_segmenter: r.loadSeconds },
    simd: simdPath, page_seconds: (performance.now() - t0) / 1000,
  });
}

readyPromise.then(async (m) => {
  simdPath = m.simd;
  status('vcar ready (' + m.simd + '): load a scene');
  if (!params.get('scene')) return;
  try { await unattended(); } catch (e) {
    status('error: ' + e.message);
    $('vcar-result').textContent = JSON.stringify({ error: e.message });
  }
});
