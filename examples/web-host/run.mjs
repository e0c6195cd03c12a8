// Loads the web host's module, makes a mask as a page would at start-up, and
// prints what it made; with OUT, writes the mask's KTX2 bytes there.
// Usage: node run.mjs MODULE.wasm [WxHxT] [DIMS] [ITERATIONS] [OUT]
import { readFileSync, writeFileSync } from 'node:fs';

const [wasm, size = '64x64x32', dims = '2', iterations = '24', out] = process.argv.slice(2);
const [w, h, t] = size.split('x').map(Number);
const module = await WebAssembly.compile(readFileSync(wasm));
const imports = WebAssembly.Module.imports(module);
console.log(`imports: ${imports.length ? imports.map((i) => `${i.module}.${i.name}`).join(', ') : 'none'}`);
const { exports } = await WebAssembly.instantiate(module, {});
const kept = () => new Uint8Array(exports.memory.buffer, exports.out_ptr(), exports.out_len());

const began = performance.now();
const ratio = exports.make(w, h, t, Number(dims), Number(iterations), 1n);
const seconds = (performance.now() - began) / 1000;
if (ratio < 0) {
  console.log(`error: ${new TextDecoder().decode(kept())}`);
  process.exit(1);
}
const ktx2 = kept().slice(); // a copy: the next call may move the kept bytes
const identifier = Array.from(ktx2.slice(1, 7), (c) => String.fromCharCode(c)).join('');
console.log(`made ${w}x${h}x${t}, d = ${dims}, ${iterations} iterations in ${seconds.toFixed(2)} s: ` +
  `objective ${ratio.toFixed(4)} x white noise, ${ktx2.length} bytes of ${identifier}`);
if (out) {
  writeFileSync(out, ktx2);
  console.log(`wrote ${out}`);
}
if (exports.make_within_a_second() < 0) {
  console.log(`a time budget: ${new TextDecoder().decode(kept())}`);
}
