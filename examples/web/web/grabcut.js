// GrabCut (OpenCV's, compiled to WebAssembly: npm @techstark/opencv-js, Apache-2.0, loaded by
// the worker from vendor/opencv/) as the page's segmenter. vcar hands each frame with the
// prompt's box in it (the user's box on the reference view; elsewhere the prompt lifted to 3D
// and boxed in the frame, vcar::lift_prompt), and this answers with GrabCut inside the box, by
// the rules of the native vcar::opencv::GrabCutSegmenter (include/vcar/opencv/grabcut_segmenter.hpp),
// so the page and `vcar segment --segmenter grabcut` agree:
//  - no box, a box thinner than minBoxPx, or one leaving less than minBackground of the frame
//    outside it: no mask (null);
//  - the frame as BGR (cropped to the box padded by ceil(context * its width) columns and
//    ceil(context * its height) rows each side when context >= 0; the rest is background),
//    cv.grabCut with the box, `iterations` rounds; on the reference view a
//    click seeds a disc of seedRadius * (image diagonal) as sure foreground (GC_INIT_WITH_MASK,
//    the box's labels otherwise);
//  - OpenCV's random generator reset to `seed` before each frame (its k-means initialisation):
//    the native segmenter's seed, so both start from the same state;
//  - foreground (GC_FGD, GC_PR_FGD) under minForeground of the box's area: no mask.
self.vcarGrabCutParams = {
  iterations: 5, seedRadius: 0.01, minBoxPx: 4, minBackground: 0.01, minForeground: 0.05, seed: 0x6C8E9CF5,
  context: -1,
};

// The page's two trade-offs of speed against accuracy (options.quality, URL quality=; the native
// twin's --quality, web_flow.hpp's quality_of: the same numbers). `full` renders the views at
// most 400 px on the long side and runs GrabCut on the whole frame, 5 iterations; `fast` renders
// at most 200 px and runs GrabCut on a crop of the box padded by its size each side, 3
// iterations: on the stage of three real objects at 640 x 480 (docs/web.md) the native twin
// took 3-4x less time for 3D F1 0.962 / 0.817 / 0.957 against 0.971 / 0.929 / 0.941 (box prompts).
self.vcarQualities = {
  full: { maxSide: 400, context: -1, iterations: 5 },
  fast: { maxSide: 200, context: 1, iterations: 3 },
};

// frame = {index, width, height, rgb (Uint8Array w*h*3), click: [u, v] | null, box: [x0, y0, x1, y1] | null, fine}
self.vcarGrabCut = function (cv, frame, params = self.vcarGrabCutParams) {
  const W = frame.width, H = frame.height, b = frame.box;
  if (!b || !b.every(Number.isFinite)) return null;
  const clamp = (v, hi) => Math.min(Math.max(v, 0), hi);
  const x0 = clamp(Math.floor(b[0]), W), y0 = clamp(Math.floor(b[1]), H);
  const x1 = clamp(Math.ceil(b[2]), W), y1 = clamp(Math.ceil(b[3]), H);
  if (x1 - x0 < params.minBoxPx || y1 - y0 < params.minBoxPx) return null;
  const outside = 1 - ((x1 - x0) * (y1 - y0)) / (W * H);
  if (outside < params.minBackground || (x1 - x0 === W && y1 - y0 === H)) return null;
  // The crop GrabCut sees (params.context), in frame pixels; the box inside it.
  let c0 = 0, r0 = 0, c1 = W, r1 = H;
  if (params.context >= 0) {
    const px = Math.ceil(params.context * (x1 - x0)), py = Math.ceil(params.context * (y1 - y0));
    c0 = Math.max(0, x0 - px); r0 = Math.max(0, y0 - py); c1 = Math.min(W, x1 + px); r1 = Math.min(H, y1 + py);
    if (c0 === x0 && r0 === y0 && c1 === x1 && r1 === y1) { c0 = 0; r0 = 0; c1 = W; r1 = H; }  // no background: the whole frame
  }
  const cw = c1 - c0, ch = r1 - r0;
  const rect = new cv.Rect(x0 - c0, y0 - r0, x1 - x0, y1 - y0);
  const rgb = cv.matFromArray(H, W, cv.CV_8UC3, frame.rgb);
  const crop = rgb.roi(new cv.Rect(c0, r0, cw, ch));
  const bgr = new cv.Mat(), labels = new cv.Mat(ch, cw, cv.CV_8UC1, new cv.Scalar(cv.GC_BGD));
  const bgd = new cv.Mat(), fgd = new cv.Mat();
  try {
    cv.cvtColor(crop, bgr, cv.COLOR_RGB2BGR);
    cv.setRNGSeed(params.seed);
    const seeded = frame.index === 0 && frame.click && params.seedRadius > 0;  // both rounds, as natively
    if (seeded) {
      const inside = labels.roi(rect);
      inside.setTo(new cv.Scalar(cv.GC_PR_FGD));
      inside.delete();
      const r = Math.max(0, Math.round(params.seedRadius * Math.hypot(W, H)));
      cv.circle(labels, new cv.Point(Math.trunc(frame.click[0]) - c0, Math.trunc(frame.click[1]) - r0), r, new cv.Scalar(cv.GC_FGD), -1);
      cv.grabCut(bgr, labels, rect, bgd, fgd, params.iterations, cv.GC_INIT_WITH_MASK);
    } else {
      cv.grabCut(bgr, labels, rect, bgd, fgd, params.iterations, cv.GC_INIT_WITH_RECT);
    }
    const m = new Uint8Array(W * H);
    let fg = 0;
    for (let i = 0; i < ch; ++i)
      for (let j = 0; j < cw; ++j) fg += m[(i + r0) * W + j + c0] = labels.data[i * cw + j] & 1;  // GC_FGD = 1, GC_PR_FGD = 3
    return fg < params.minForeground * rect.width * rect.height ? null : m;
  } finally {
    for (const mat of [rgb, crop, bgr, labels, bgd, fgd]) mat.delete();
  }
};
