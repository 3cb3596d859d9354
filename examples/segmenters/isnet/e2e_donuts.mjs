#!/usr/bin/env node
// End to end on real trained Gaussians: two donuts (tests/data/donut.ply, and a copy of it
// 0.3 to the side, tilted 60 degrees), a forward capture that sees both side by side, the first
// donut the target. `vcar segment --segmenter-cmd "node .../isnet.mjs" --box ...` (the box: the
// target's bounding box in the reference view), then the scores:
//   2D: ISNet's masks of the training views (coarse round) against the target's silhouette (the
//       alpha > 0.5 of the donut rendered alone; the views are chosen so the donuts never
//       overlap, so the silhouette is the visible part; checked);
//   3D: precision / recall of the selected Gaussians (the target's are the scene's first n);
//   held out: IoU of the selection's render (alpha > 0.5) with the silhouette, 4 other views.
// A measurement, not a pass/fail test.
//
// --with-boxes: also what prompt.json "boxes" will give (not sent by vcar yet): the coarse
// request again, with "boxes" = each view's bounding box of the target's silhouette (exact
// boxes, an upper bound), then `vcar segment --masks` on those masks (no SSS: a folder has no
// masks of sampled views), scored the same way.
//
//   node e2e_donuts.mjs VCAR DONUT.ply WORK_DIR [--no-sss] [--no-box] [--with-boxes] [--size WxH]

import fs from 'node:fs';
import path from 'node:path';
import { spawnSync } from 'node:child_process';
import { fileURLToPath } from 'node:url';

const HERE = path.dirname(fileURLToPath(import.meta.url));
const args = process.argv.slice(2);
const flag = (f) => { const i = args.indexOf(f); if (i < 0) return false; args.splice(i, 1); return true; };
const value = (f, d) => { const i = args.indexOf(f); if (i < 0) return d; const v = args[i + 1]; args.splice(i, 2); return v; };
const noSss = flag('--no-sss'), noBox = flag('--no-box'), withBoxes = flag('--with-boxes');
const [W, H] = value('--size', '480x360').split('x').map(Number);
if (args.length !== 3) { console.error('usage: node e2e_donuts.mjs VCAR DONUT.ply WORK_DIR [--no-sss] [--no-box] [--with-boxes] [--size WxH]'); process.exit(64); }
const [VCAR, DONUT, WORK] = args;
const { PNG } = await import('pngjs');

function vcar(a) {
  const t = Date.now();
  const p = spawnSync(VCAR, a, { encoding: 'utf8' });
  if (p.status !== 0) { console.error(`vcar ${a.join(' ')}: status ${p.status}\n${p.stdout}${p.stderr}`); process.exit(1); }
  return { out: p.stdout, seconds: (Date.now() - t) / 1000 };
}
const readMask = (file) => { const m = PNG.sync.read(fs.readFileSync(file)); return Uint8Array.from({ length: m.width * m.height }, (_, i) => m.data[4 * i] >= 128); };
const iou = (a, b) => { let i = 0, u = 0; for (let k = 0; k < a.length; ++k) { i += a[k] && b[k]; u += a[k] || b[k]; } return u ? i / u : 1; };

// ---- the scene: the donut and its tilted copy ---------------------------------------------------
const data = fs.readFileSync(DONUT);
const end = data.indexOf('end_header\n') + 'end_header\n'.length;
const header = data.toString('latin1', 0, end);
const props = header.split('\n').filter((l) => l.startsWith('property')).map((l) => l.split(' ')[2]);
const expected = 'x,y,z,f_dc_0,f_dc_1,f_dc_2,opacity,scale_0,scale_1,scale_2,rot_0,rot_1,rot_2,rot_3';
if (props.join() !== expected || !header.includes('binary_little_endian')) { console.error(`${DONUT}: expected the float properties ${expected}`); process.exit(1); }
const K = props.length;
const n = Number(/element vertex (\d+)/.exec(header)[1]);
const src = new Float32Array(data.buffer.slice(data.byteOffset + end, data.byteOffset + end + n * K * 4));
const median = (d) => Float32Array.from({ length: n }, (_, i) => src[i * K + d]).sort()[n >> 1];
const c = [median(0), median(1), median(2)];
const copy = new Float32Array(src);
const a = Math.PI / 3, ca = Math.cos(a), sa = Math.sin(a); // 60 degrees about x
const qr = [Math.cos(a / 2), Math.sin(a / 2), 0, 0];
for (let i = 0; i < n; ++i) {
  const o = i * K, y = src[o + 1] - c[1], z = src[o + 2] - c[2];
  copy[o] = src[o] + 0.3;
  copy[o + 1] = c[1] + ca * y - sa * z;
  copy[o + 2] = c[2] + sa * y + ca * z;
  const [w1, x1, y1, z1] = qr, [w2, x2, y2, z2] = [src[o + 10], src[o + 11], src[o + 12], src[o + 13]];
  copy[o + 10] = w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2;
  copy[o + 11] = w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2;
  copy[o + 12] = w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2;
  copy[o + 13] = w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2;
}
const writePly = (file, parts) => {
  const count = parts.reduce((s, p) => s + p.length / K, 0);
  fs.writeFileSync(file, Buffer.concat([Buffer.from(header.replace(/element vertex \d+/, `element vertex ${count}`), 'latin1'), ...parts.map((p) => Buffer.from(p.buffer))]));
};
fs.rmSync(WORK, { recursive: true, force: true });
fs.mkdirSync(WORK, { recursive: true });
const scene = path.join(WORK, 'scene.ply'), target = path.join(WORK, 'target.ply'), other = path.join(WORK, 'other.ply');
writePly(scene, [src, copy]);
writePly(target, [src]);
writePly(other, [copy]);

// ---- cameras: from the -y side, looking at the midpoint of the donuts ---------------------------
const norm = (v) => { const l = Math.hypot(...v); return v.map((x) => x / l); };
const cross = (u, v) => [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
const mid = [c[0] + 0.15, c[1], c[2]];
function camera(name, id, elevDeg, azDeg) {
  const el = elevDeg * Math.PI / 180, az = (azDeg - 90) * Math.PI / 180;
  const d = [Math.cos(el) * Math.cos(az), Math.cos(el) * Math.sin(az), Math.sin(el)];
  const eye = mid.map((m, i) => m + 0.7 * d[i]);
  const z = norm(mid.map((m, i) => m - eye[i])), x = norm(cross(z, [0, 0, 1])), y = cross(z, x);
  const f = 0.5 * W / Math.tan(25 * Math.PI / 180);
  return { id, img_name: name, width: W, height: H, position: eye, rotation: [0, 1, 2].map((i) => [x[i], y[i], z[i]]), fx: f, fy: f };
}
const train = [], held = [];
[[25, -30], [25, -10], [25, 10], [25, 30], [50, -30], [50, -10], [50, 10], [50, 30]].forEach(([e, az], k) => train.push(camera(`train_${k}`, k, e, az)));
[[35, -20], [35, 0], [35, 20], [60, 0]].forEach(([e, az], k) => held.push(camera(`eval_${k}`, k, e, az)));
const trainJson = path.join(WORK, 'cameras.json'), heldJson = path.join(WORK, 'eval_cameras.json');
fs.writeFileSync(trainJson, JSON.stringify(train, null, 1));
fs.writeFileSync(heldJson, JSON.stringify(held, null, 1));

// Silhouettes: each donut rendered alone, alpha >= 0.5 (the renderer's alpha PNG, >= 128).
const sil = {};
for (const [tag, ply] of [['target', target], ['other', other]])
  for (const [cams, set] of [[trainJson, 'train'], [heldJson, 'held']]) {
    const dir = path.join(WORK, `${tag}_${set}`);
    vcar(['-q', 'render', '--scene', ply, '--cameras', cams, '--all-views', '--out', dir, '--alpha', `${dir}_alpha`]);
    for (const f of fs.readdirSync(`${dir}_alpha`)) sil[`${tag}/${f.replace('.png', '')}`] = readMask(path.join(`${dir}_alpha`, f));
  }
for (const cam of [...train, ...held]) {
  const t = sil[`target/${cam.img_name}`], o = sil[`other/${cam.img_name}`];
  if (t.some((v, i) => v && o[i])) { console.error(`${cam.img_name}: the donuts overlap in the image: the silhouette is not the visible part`); process.exit(1); }
  if (t.every((v) => !v)) { console.error(`${cam.img_name}: the target is not in view`); process.exit(1); }
}

// ---- vcar segment ---------------------------------------------------------------------------------
const out = path.join(WORK, 'out');
function bbox(m) {
  let x0 = W, y0 = H, x1 = 0, y1 = 0;
  m.forEach((v, i) => { if (v) { const x = i % W, y = (i / W) | 0; x0 = Math.min(x0, x); y0 = Math.min(y0, y); x1 = Math.max(x1, x + 1); y1 = Math.max(y1, y + 1); } });
  return [x0, y0, x1, y1];
}
const ref = sil['target/train_0'];
let sx = 0, sy = 0, cnt = 0;
ref.forEach((v, i) => { if (v) { sx += i % W; sy += (i / W) | 0; ++cnt; } });
let px = Math.round(sx / cnt), py = Math.round(sy / cnt);
if (!ref[py * W + px]) { const i = ref.findIndex((v, k) => v && Math.abs((k % W) - px) + Math.abs(((k / W) | 0) - py) < 40); px = i % W; py = (i / W) | 0; } // the centroid falls in the hole
const seg = ['segment', '--scene', scene, '--cameras', trainJson, '--prompt-view', 'train_0', '--points', `${px},${py}`,
  '--segmenter-cmd', `node ${path.join(HERE, 'isnet.mjs')}`, '--keep-requests', '--out', out];
if (!noBox) seg.push('--box', bbox(ref).join(','));
if (noSss) seg.push('--set', 'enable_sss=false');
console.log(`vcar ${seg.join(' ')}`);
const s = vcar(seg);
process.stdout.write(s.out);

const mean = (v) => v.reduce((p, q) => p + q, 0) / v.length;
// 2D: masks of the training views (`cams`: a request's cameras.json) against the target's silhouette.
function score2d(cams, maskDir) {
  const ious = [];
  for (const cam of cams) {
    const mFile = path.join(maskDir, `${cam.img_name}.png`);
    if (!fs.existsSync(mFile)) { console.log(`  2D ${cam.view}: no mask`); continue; }
    const m = readMask(mFile);
    ious.push(iou(m, sil[`target/${cam.view}`]));
    const both = iou(m, sil[`target/${cam.view}`].map((v, i) => v || sil[`other/${cam.view}`][i]));
    console.log(`  2D ${cam.view}: IoU ${ious.at(-1).toFixed(3)} with the target (${both.toFixed(3)} with both donuts)`);
  }
  console.log(`2D mean IoU (${ious.length} training views): ${mean(ious).toFixed(3)}`);
}
// 3D (selected Gaussians) and held out (the selection's render against the silhouettes).
function score3d(outDir, label, seconds) {
  const sel = JSON.parse(fs.readFileSync(path.join(outDir, 'selection.json'), 'utf8')).indices;
  const tp = sel.filter((i) => i < n).length;
  const heldDir = path.join(outDir, 'held_selection');
  vcar(['-q', 'render', '--scene', scene, '--cameras', heldJson, '--all-views', '--selection', path.join(outDir, 'selection.json'), '--out', heldDir, '--alpha', `${heldDir}_alpha`]);
  const heldIou = held.map((cam) => iou(readMask(path.join(`${heldDir}_alpha`, `${cam.img_name}.png`)), sil[`target/${cam.img_name}`]));
  const rep = JSON.parse(fs.readFileSync(path.join(outDir, 'report.json'), 'utf8'));
  console.log(`3D (${label}): ${sel.length} selected, precision ${(tp / Math.max(1, sel.length)).toFixed(3)}, recall ${(tp / n).toFixed(3)} (target ${n} of ${2 * n} Gaussians); ` +
    `held-out mIoU ${mean(heldIou).toFixed(3)} (${heldIou.map((v) => v.toFixed(3)).join(', ')}); SSS ${rep.sss_triggered}, ${rep.sampled_views} sampled views; segment ${seconds.toFixed(0)} s`);
}
const reqs = fs.readdirSync(path.join(out, 'requests')).sort();
for (const req of reqs) {
  const log = fs.readFileSync(path.join(out, 'requests', req, 'segmenter.log'), 'utf8').trim().split('\n').at(-1);
  console.log(`${req}: ${JSON.parse(fs.readFileSync(path.join(out, 'requests', req, 'cameras.json'), 'utf8')).length} frames; ${log}`);
}
const coarse = path.join(out, 'requests', reqs[0]); // the coarse round: the training views
const coarseCams = JSON.parse(fs.readFileSync(path.join(coarse, 'cameras.json'), 'utf8'));
console.log('coarse round, prompt as vcar sends it today:');
score2d(coarseCams, path.join(coarse, 'masks'));
score3d(out, 'vcar segment --segmenter-cmd', s.seconds);

if (withBoxes) {
  const bdir = path.join(WORK, 'boxes_request');
  fs.cpSync(path.join(coarse, 'frames'), path.join(bdir, 'frames'), { recursive: true });
  fs.copyFileSync(path.join(coarse, 'cameras.json'), path.join(bdir, 'cameras.json'));
  fs.mkdirSync(path.join(bdir, 'masks'));
  const prompt = JSON.parse(fs.readFileSync(path.join(coarse, 'prompt.json'), 'utf8'));
  prompt.boxes = coarseCams.map((cam) => bbox(sil[`target/${cam.view}`]));
  fs.writeFileSync(path.join(bdir, 'prompt.json'), JSON.stringify(prompt));
  const p = spawnSync(process.execPath, [path.join(HERE, 'isnet.mjs'), bdir], { encoding: 'utf8' });
  if (p.status !== 0) { console.error(`isnet.mjs on ${bdir}: status ${p.status}\n${p.stdout}${p.stderr}`); process.exit(1); }
  console.log(`with "boxes" (each view's exact target box): ${p.stdout.trim().split('\n').at(-1)}`);
  score2d(coarseCams, path.join(bdir, 'masks'));
  const mdir = path.join(WORK, 'boxes_masks');
  fs.mkdirSync(mdir);
  for (const cam of coarseCams) fs.copyFileSync(path.join(bdir, 'masks', `${cam.img_name}.png`), path.join(mdir, `${cam.view}.png`));
  const outB = path.join(WORK, 'out_boxes');
  const sb = vcar(['segment', '--scene', scene, '--cameras', trainJson, '--prompt-view', 'train_0', '--masks', mdir, '--set', 'enable_sss=false', '--out', outB]);
  process.stdout.write(sb.out);
  score3d(outB, 'vcar segment --masks of the boxed request, no SSS', sb.seconds);
}
