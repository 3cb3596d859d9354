// Times the browser flow of a vcar.js build under Node (V8, the engine of Chromium) without a
// page: load the scene (and cameras), pick the view, segment at the click; prints one JSON line
// with the median of `reps` segment() calls. Used by bench_web.sh to compare WebAssembly builds
// (-msimd128 or not) on the same machine in the same run.
//   node node_flow.cjs VCAR_JS SCENE CAMERAS|- VIEW|- U,V [REPS]
const fs = require('fs');
const [vcarJs, scene, cameras, view, click, reps = '3'] = process.argv.slice(2);
const createVcar = require(require('path').resolve(vcarJs));
(async () => {
  const vcar = await createVcar();
  const s = new vcar.Session();
  s.loadScene(fs.readFileSync(scene), scene);
  if (cameras !== '-') s.loadCameras(fs.readFileSync(cameras), cameras);
  const cam = s.referenceView(view === '-' ? '' : view);
  const [u, v] = click.split(',').map(Number);
  const times = [];
  let selected = 0;
  for (let r = 0; r < Number(reps); ++r) {
    const t0 = process.hrtime.bigint();
    try { s.segment(cam, u, v, {}, null); } catch (e) { throw new Error(typeof e === 'number' ? vcar.exceptionMessage(e) : e); }
    times.push(Number(process.hrtime.bigint() - t0) / 1e9);
    selected = s.indices().length;
  }
  times.sort((a, b) => a - b);
  console.log(JSON.stringify({ build: vcarJs, simd: vcar.simdPath(), selected, median_s: times[times.length >> 1], times }));
})().catch((e) => { console.error(String(e.message || e).slice(0, 500)); process.exit(1); });
