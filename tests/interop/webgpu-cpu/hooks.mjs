// Module resolution hook: every `webgpu` import except the shim's own gets the shim.
const shim = new URL('./webgpu-shim.mjs', import.meta.url).href;
export async function resolve(specifier, context, next) {
  if (specifier === 'webgpu' && context.parentURL !== shim) return { url: shim, shortCircuit: true };
  return next(specifier, context);
}
