// Prints where d3-hexjson draws each hex of a HexJSON file: {"key": [x, y], ...}, in the SVG
// pixels of a width × height drawing (x right, y DOWN), as renderHexJSON(hexjson, width, height)
// computes them (it returns the hexes with their centre in `x`, `y`).
//
//   node tests/hexjson/centres.mjs FILE.hexjson WIDTH HEIGHT [NODE_MODULES_DIR]
//
// d3-hexjson is looked up from NODE_MODULES_DIR (default: $HEXJSON_NODE_MODULES, else this
// folder's own resolution), so it can live in a cache such as target/hexjson-node
// (scripts/test-hexjson.sh installs it there). Needs Node >= 18.
import { readFileSync } from "node:fs";
import { createRequire } from "node:module";
import { join, resolve } from "node:path";

const [file, width, height, modules = process.env.HEXJSON_NODE_MODULES] = process.argv.slice(2);
if (!file || !(Number(width) > 0) || !(Number(height) > 0)) {
    console.error("usage: node centres.mjs FILE.hexjson WIDTH HEIGHT [NODE_MODULES_DIR]");
    process.exit(2);
}
// d3-hexjson's package main is a UMD build (CommonJS under Node): require it from the cache.
const require = createRequire(
    modules ? join(resolve(modules), "..", "resolve-from-here.js") : import.meta.url,
);
const { renderHexJSON } = require("d3-hexjson");

const hexjson = JSON.parse(readFileSync(file, "utf8"));
const centres = {};
for (const hex of renderHexJSON(hexjson, Number(width), Number(height))) {
    centres[hex.key] = [hex.x, hex.y];
}
process.stdout.write(JSON.stringify(centres) + "\n");
