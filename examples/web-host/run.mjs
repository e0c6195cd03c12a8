// Loads the web host's module, makes a mask as a page would at start-up, and
// prints what it made; with OUT, writes the mask's KTX2 bytes there. With
// --scene, makes every mask of a scene file's plan instead and, with OUT, writes
// the plan block to OUT.block and the stacked texels to OUT.texels.
// Usage: node run.mjs MODULE.wasm [WxHxT] [DIMS] [ITERATIONS] [OUT]
//        node run.mjs MODULE.wasm --scene SCENE.toml [OUT]
import { readFileSync, writeFileSync } from 'node:fs';

const module = await WebAssembly.compile(readFileSync(process.argv[2]));
const imports = WebAssembly.Module.imports(module);
console.log(`imports: ${imports.length ? imports.map((i) => `${i.module}.${i.name}`).join(', ') : 'none'}`);
const { exports } = await WebAssembly.instantiate(module, {});
const kept = () => new Uint8Array(exports.memory.buffer, exports.out_ptr(), exports.out_len());

if (process.argv[3] === '--scene') {
  const [, , , , scene, out] = process.argv;
  const text = readFileSync(scene);
  const at = exports.input(text.length); // may grow the memory: view it after
  new Uint8Array(exports.memory.buffer, at, text.length).set(text);
  const began = performance.now();
  const block = exports.make_plan();
  const seconds = (performance.now() - began) / 1000;
  if (block < 0) {
    console.log(`error: ${new TextDecoder().decode(kept())}`);
    process.exit(1);
  }
  const bytes = kept().slice();
  console.log(`made the plan in ${seconds.toFixed(2)} s: a ${block}-byte block, ${bytes.length - block} bytes of texels`);
  if (out) {
    writeFileSync(`${out}.block`, bytes.subarray(0, block));
    writeFileSync(`${out}.texels`, bytes.subarray(block));
    console.log(`wrote ${out}.block and ${out}.texels`);
  }
  process.exit(0);
}

const [, , , size = '64x64x32', dims = '2', iterations = '24', out] = process.argv;
const [w, h, t] = size.split('x').map(Number);

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
