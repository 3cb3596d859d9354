#!/usr/bin/env node
// End to end: `vcar synth`, then `vcar segment --segmenter-cmd "node .../isnet.mjs"` on it, then
// `vcar eval`; prints the 2D IoU of ISNet's masks of the training views (coarse round) against the
// dataset's ground-truth masks, and the 3D result. A measurement, not a pass/fail test.
//
//   node e2e_synth.mjs VCAR WORK_DIR [--sss] [--box] [--seed N] [--gaussians N] [--views N] [--size WxH]
//
// --box: prompt the reference view with the bounding box of its ground-truth mask (vcar segment
// --box, prompt.json "box"); otherwise only the dataset's points, which ISNet cannot use: every
// frame is then segmented whole. Without --sss spiral sampling is off (enable_sss=false).

import fs from 'node:fs';
import path from 'node:path';
import { spawnSync } from 'node:child_process';
import { fileURLToPath } from 'node:url';

const HERE = path.dirname(fileURLToPath(import.meta.url));
const args = process.argv.slice(2);
const flag = (f) => { const i = args.indexOf(f); if (i < 0) return false; args.splice(i, 1); return true; };
const value = (f, d) => { const i = args.indexOf(f); if (i < 0) return d; const v = args[i + 1]; args.splice(i, 2); return v; };
const sss = flag('--sss'), useBox = flag('--box');
const seed = value('--seed', '3'), gaussians = value('--gaussians', '20000'), nviews = value('--views', '8');
const [w, h] = value('--size', '320x240').split('x');
if (args.length !== 2) { console.error('usage: node e2e_synth.mjs VCAR WORK_DIR [--sss] [--box] [--seed N] [--gaussians N] [--views N] [--size WxH]'); process.exit(64); }
const [VCAR, WORK] = args;
const { PNG } = await import('pngjs');

function vcar(a) {
  const t = Date.now();
  const p = spawnSync(VCAR, a, { encoding: 'utf8' });
  if (p.status !== 0) { console.error(`vcar ${a.join(' ')}: status ${p.status}\n${p.stdout}${p.stderr}`); process.exit(1); }
  return { out: p.stdout, seconds: (Date.now() - t) / 1000 };
}
const fg = (file) => { const m = PNG.sync.read(fs.readFileSync(file)); return { w: m.width, h: m.height, on: Uint8Array.from({ length: m.width * m.height }, (_, i) => m.data[4 * i] >= 128) }; };

fs.rmSync(WORK, { recursive: true, force: true });
const ds = path.join(WORK, 'dataset'), out = path.join(WORK, 'out');
vcar(['-q', 'synth', '--rig', 'forward', '--seed', seed, '--gaussians', gaussians, '--views', nviews, '--width', w, '--height', h, '--out', ds]);
const prompt = JSON.parse(fs.readFileSync(path.join(ds, 'prompt.json'), 'utf8'));
const seg = ['segment', '--scene', path.join(ds, 'scene.ply'), '--cameras', path.join(ds, 'cameras.json'),
  '--prompt-view', prompt.reference_view, '--points', prompt.points.map((p) => p.join(',')).join(';'),
  '--segmenter-cmd', `node ${path.join(HERE, 'isnet.mjs')}`, '--keep-requests', '--out', out];
if (useBox) {
  const m = fg(path.join(ds, 'masks', `${prompt.reference_view}.png`));
  let x0 = m.w, y0 = m.h, x1 = 0, y1 = 0;
  m.on.forEach((v, i) => { if (v) { const x = i % m.w, y = (i / m.w) | 0; x0 = Math.min(x0, x); y0 = Math.min(y0, y); x1 = Math.max(x1, x + 1); y1 = Math.max(y1, y + 1); } });
  seg.push('--box', [x0, y0, x1, y1].join(','));
}
if (!sss) seg.push('--set', 'enable_sss=false');
const s = vcar(seg);
process.stdout.write(s.out);

// 2D: the coarse round's masks (the training views) against the ground truth.
const req = fs.readdirSync(path.join(out, 'requests')).sort()[0];
const cams = JSON.parse(fs.readFileSync(path.join(out, 'requests', req, 'cameras.json'), 'utf8'));
const ious = [];
for (const c of cams) {
  const gtFile = path.join(ds, 'masks', `${c.view.replace(/\.[a-z]+$/, '')}.png`), mFile = path.join(out, 'requests', req, 'masks', `${c.img_name}.png`);
  if (!fs.existsSync(mFile)) { console.log(`2D ${c.view}: no mask`); continue; }
  const g = fg(gtFile), m = fg(mFile);
  let inter = 0, uni = 0;
  for (let i = 0; i < g.on.length; ++i) { inter += g.on[i] && m.on[i]; uni += g.on[i] || m.on[i]; }
  ious.push(uni ? inter / uni : 1);
  console.log(`2D ${c.view}: IoU ${ious.at(-1).toFixed(3)}`);
}
const mean = ious.reduce((a, b) => a + b, 0) / ious.length;
const ev = JSON.parse(vcar(['eval', '--dataset', ds, '--selection', path.join(out, 'selection.json'), '--json']).out);
const rep = JSON.parse(fs.readFileSync(path.join(out, 'report.json'), 'utf8'));
console.log(`2D mean IoU (coarse round, ${ious.length} training views): ${mean.toFixed(3)}`);
console.log(`3D held-out mIoU ${ev.mIoU.toFixed(3)}, precision_3d ${ev.precision_3d.toFixed(3)}, recall_3d ${ev.recall_3d.toFixed(3)}, f1_3d ${ev.f1_3d.toFixed(3)}; ` +
  `${rep.counts.final} Gaussians selected; sss ${rep.sss_triggered}, ${rep.sampled_views} sampled views; segment took ${s.seconds.toFixed(0)} s`);
