// Lets splat-transform's GPU voxelisation (--filter-cluster) run where Dawn has no GPU adapter,
// e.g. a CI machine: Dawn's OpenGL backend in compatibility mode on Mesa's llvmpipe (EGL
// surfaceless; Debian packages libegl1 libegl-mesa0 libgl1-mesa-dri). Chosen once per process
// (two Dawn instances in one process crash): VCAR_WEBGPU=cpu forces it, =native forbids it, and
// the default takes it when the machine shows no GPU device (/dev/nvidia0, /dev/dri/renderD*).
import { existsSync, readdirSync } from 'node:fs';
import { create as dawnCreate, globals } from 'webgpu';

export { globals };

const hasGpuDevice = () => {
  if (existsSync('/dev/nvidia0')) return true;
  try {
    return readdirSync('/dev/dri').some((f) => f.startsWith('renderD'));
  } catch {
    return false;
  }
};
const mode = process.env.VCAR_WEBGPU || 'auto';
const cpu = mode === 'cpu' || (mode === 'auto' && !hasGpuDevice());

export function create(options = []) {
  if (!cpu) return dawnCreate(options);
  if (!process.env.EGL_PLATFORM) process.env.EGL_PLATFORM = 'surfaceless';
  const gpu = dawnCreate([...options.filter((x) => !x.startsWith('adapter=')), 'backend=opengl']);
  const request = gpu.requestAdapter.bind(gpu);
  return new Proxy(gpu, {
    get(target, prop) {
      if (prop === 'requestAdapter') return (o = {}) => request({ ...o, featureLevel: 'compatibility' });
      const v = Reflect.get(target, prop);
      return typeof v === 'function' ? v.bind(target) : v;
    },
  });
}
