// Runs @mapbox/martini (RTIN) on a float32 grid for tests/bench/roam.c.
// Usage: node martini.js MARTINI_DIR DEM.f32 SIZE E1,E2,... OUTPREFIX RUNS
// For each error E: median time of RUNS x (createTile + getMesh(E)) after a
// warm-up (and the fastest of them, last column), and the mesh written to OUTPREFIX<k>.bin as
// u32 vertex count, u32 triangle count, u16 (x, y) per vertex, u32 x3 per triangle.
'use strict';
const fs = require('fs');
const path = require('path');
const [dir, file, sizeStr, errs, prefix, runsStr] = process.argv.slice(2);
const Martini = require(path.resolve(dir, 'martini.js'));
const size = Number(sizeStr), runs = Number(runsStr) || 5;
const buf = fs.readFileSync(file);
const terrain = new Float32Array(buf.buffer.slice(buf.byteOffset, buf.byteOffset + size * size * 4));
const ms = (a, b) => Number(b - a) / 1e6;
const median = (a) => { const s = [...a].sort((x, y) => x - y); return s[Math.floor(s.length / 2)]; };
let t0 = process.hrtime.bigint();
const martini = new Martini(size);
const initMs = ms(t0, process.hrtime.bigint());
// cold run first (what a one-shot tool pays), then warm runs
t0 = process.hrtime.bigint();
martini.createTile(terrain).getMesh(Number(errs.split(',')[0]));
const coldMs = ms(t0, process.hrtime.bigint());
errs.split(',').forEach((e, k) => {
    const E = Number(e);
    const times = [], build = [];
    let mesh;
    for (let r = 0; r < runs; r++) {
        const a = process.hrtime.bigint();
        const tile = martini.createTile(terrain);
        const b = process.hrtime.bigint();
        mesh = tile.getMesh(E);
        const c = process.hrtime.bigint();
        times.push(ms(a, c));
        build.push(ms(a, b));
    }
    const nv = mesh.vertices.length / 2, nt = mesh.triangles.length / 3;
    const out = Buffer.alloc(8 + nv * 4 + nt * 12);
    out.writeUInt32LE(nv, 0);
    out.writeUInt32LE(nt, 4);
    Buffer.from(mesh.vertices.buffer, mesh.vertices.byteOffset, nv * 4).copy(out, 8);
    Buffer.from(mesh.triangles.buffer, mesh.triangles.byteOffset, nt * 12).copy(out, 8 + nv * 4);
    fs.writeFileSync(prefix + k + '.bin', out);
    console.log(`${E} ${median(times).toFixed(3)} ${median(build).toFixed(3)} ${nt} ${initMs.toFixed(3)} ${coldMs.toFixed(3)} ${Math.min(...times).toFixed(3)}`);
});
