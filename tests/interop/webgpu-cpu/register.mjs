// node --import <this file>: routes splat-transform's `import 'webgpu'` through webgpu-shim.mjs.
import { register } from 'node:module';
register('./hooks.mjs', import.meta.url);
