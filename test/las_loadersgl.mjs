// test/las_loadersgl.mjs: LAS files read by loaders.gl (@loaders.gl/las,
// from npm), the independent reader test/cli_las.sh compares ./tdc's with.
//
//   node test/las_loadersgl.mjs NPMDIR PARSER OUTDIR FILE...
//
// NPMDIR holds node_modules/@loaders.gl/las (the version cli_las.sh pins).
// PARSER is laz-perf, its public LASLoader (LAS 1.0 to 1.3, formats 0 to
// 3), or laz-rs, the parser of its LAZRsLoader (up to 1.4, formats 0 to
// 10), called directly with its WebAssembly module loaded from the file:
// the loader itself fetches it, which Node cannot do from a file URL.
// For each FILE, OUTDIR/<its name>.PARSER.txt gets one line per point, in
// file order: "x y z" as JavaScript prints a double (the shortest string
// that reads back to it), computed by loaders.gl as X * scale + offset.
import { readFileSync, writeFileSync } from 'node:fs';
import { basename } from 'node:path';
import { pathToFileURL } from 'node:url';

const [npmdir, parser, outdir, ...files] = process.argv.slice(2);
const dist = `${npmdir}/node_modules/@loaders.gl/las/dist`;
const options = { las: { shape: 'mesh', fp64: true, skip: 1, colorDepth: 8 } };
let parse;
if (parser === 'laz-perf') {
	const las = await import(pathToFileURL(`${dist}/index.js`));
	parse = (ab) => las.LASLoader.parse(ab, options);
} else if (parser === 'laz-rs') {
	const wasm = await import(pathToFileURL(`${dist}/libs/laz-rs-wasm/laz_rs_wasm.js`));
	wasm.initSync({ module: readFileSync(`${dist}/libs/laz-rs-wasm/laz_rs_wasm_bg.wasm`) });
	const rs = await import(pathToFileURL(`${dist}/lib/laz-rs-wasm/parse-las.js`));
	parse = async (ab) => rs.parseLAS(ab, options);
} else {
	throw new Error(`unknown parser ${parser}`);
}
for (const f of files) {
	const buf = readFileSync(f);
	const mesh = await parse(buf.buffer.slice(buf.byteOffset, buf.byteOffset + buf.byteLength));
	const p = mesh.attributes.POSITION.value;
	const lines = [];
	for (let i = 0; i < p.length; i += 3)
		lines.push(`${p[i]} ${p[i + 1]} ${p[i + 2]}\n`);
	writeFileSync(`${outdir}/${basename(f)}.${parser}.txt`, lines.join(''));
}
