#!/usr/bin/env node
// Every C++ file of renderer/, server/, tests/ and bench/ is laid out as .clang-format says:
// runs `clang-format --dry-run --Werror` over them and lists the files that differ. Exits 77
// (skipped) where clang-format is not installed; `make format` rewrites the files in place.
//
//   node tests/style/check_format.mjs --root <repo> [--clang-format /usr/bin/clang-format]
import { spawnSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';

const DIRS = ['renderer', 'server', 'tests', 'bench'];

export function cxxFiles(repo) {
  const walk = (dir) => (fs.existsSync(dir) ? fs.readdirSync(dir, { withFileTypes: true }) : []).flatMap((e) => {
    const p = path.join(dir, e.name);
    if (e.isDirectory()) return e.name === 'node_modules' ? [] : walk(p);
    return /\.(h|hpp|cpp|cc)$/.test(e.name) ? [p] : [];
  });
  return DIRS.flatMap((d) => walk(path.join(repo, d))).sort();
}

const args = process.argv.slice(2);
const opt = (name, dflt) => (args.includes(name) ? args[args.indexOf(name) + 1] : dflt);
const repo = path.resolve(opt('--root', path.join(path.dirname(new URL(import.meta.url).pathname), '../..')));
const tool = opt('--clang-format', 'clang-format');
if (spawnSync(tool, ['--version']).status !== 0) {
  console.log(`${tool} not found: format check skipped`);
  process.exit(77);
}
const files = cxxFiles(repo);
const differ = [];
for (let i = 0; i < files.length; i += 50) {
  const batch = files.slice(i, i + 50);
  const run = spawnSync(tool, ['--dry-run', '--Werror', '--style=file', ...batch], { cwd: repo, encoding: 'utf8' });
  if (run.status === 0) continue;
  for (const line of run.stderr.split('\n')) {
    const m = /^(\S+?):\d+:\d+: error/.exec(line);
    if (m && !differ.includes(m[1])) differ.push(m[1]);
  }
  if (!differ.length) { console.error(run.stderr); process.exit(1); }
}
for (const f of differ) console.error(`${path.relative(repo, f)}: not formatted (make format)`);
console.log(differ.length ? `${differ.length} of ${files.length} files not formatted` : `${files.length} files formatted`);
process.exit(differ.length ? 1 : 0);
