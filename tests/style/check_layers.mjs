#!/usr/bin/env node
// Include-direction check. renderer/src and server/src are each split into groups stacked in
// layers; a file may include headers of its own group and of groups below it, never above, so
// the groups cannot form a cycle. Every internal include names its group ("device/vk_context.h").
// The renderer is below the server and knows nothing of HTTP; the server sees the renderer only
// through its public headers (brdfa/...) and includes no Vulkan header.
//
//   node tests/style/check_layers.mjs --root <repo>      exit 1 and list each violation
//   node tests/style/check_layers.mjs --selftest         breaks a copy on purpose, expects failure
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';

// Bottom to top. docs/design.md (Architecture) explains what each group holds.
export const TREES = [
  {
    root: 'renderer/src',
    order: ['core', 'device', 'programs', 'assets', 'analysis', 'render', 'isolation'],
    // Folders outside root that sit above every group, and may include any of them.
    above: ['renderer/worker'],
    forbid: [/^httplib\.h$/, /^brdfa_server\//],
  },
  {
    root: 'server/src',
    order: ['util', 'metrics', 'http', 'config', 'auth', 'storage', 'json', 'jobs', 'sessions', 'service', 'api', 'app'],
    above: [],
    forbid: [/^vulkan\//, /^glslang\//],
  },
];

const INCLUDE = /^\s*#\s*include\s*([<"])([^>"]+)[>"]/;

function sourceFiles(dir) {
  if (!fs.existsSync(dir)) return [];
  const out = [];
  for (const entry of fs.readdirSync(dir, { withFileTypes: true })) {
    const p = path.join(dir, entry.name);
    if (entry.isDirectory()) out.push(...sourceFiles(p));
    else if (/\.(h|hpp|cpp|cc)$/.test(entry.name)) out.push(p);
  }
  return out;
}

// The group an include names, or null for one that names none of the tree's groups.
function groupOf(target, tree) {
  const first = target.split('/')[0];
  return target.includes('/') && tree.order.includes(first) ? first : null;
}

function checkFile(file, rel, level, tree, problems) {
  const lines = fs.readFileSync(file, 'utf8').split('\n');
  lines.forEach((line, i) => {
    const m = INCLUDE.exec(line);
    if (!m) return;
    const [, delim, target] = m;
    const where = `${rel}:${i + 1}`;
    if (tree.forbid.some((re) => re.test(target))) {
      problems.push(`${where}: includes <${target}>, which ${tree.root} must not depend on`);
      return;
    }
    if (delim !== '"' || target.startsWith('brdfa/')) return;   // system or public header
    const group = groupOf(target, tree);
    if (group === null) {
      problems.push(`${where}: "${target}" does not name its group (${tree.order.join(', ')})`);
      return;
    }
    const at = tree.order.indexOf(group);
    if (at > level) {
      const own = level === Infinity ? 'the top' : tree.order[level];
      problems.push(`${where}: ${own} includes "${target}" of the higher group ${group}`);
    }
  });
}

export function check(repo) {
  const problems = [];
  for (const tree of TREES) {
    const base = path.join(repo, tree.root);
    if (!fs.existsSync(base)) { problems.push(`${tree.root}: missing`); continue; }
    for (const entry of fs.readdirSync(base, { withFileTypes: true })) {
      const rel = path.join(tree.root, entry.name);
      if (!entry.isDirectory()) { problems.push(`${rel}: a file outside every group`); continue; }
      if (!tree.order.includes(entry.name)) { problems.push(`${rel}: a group missing from the layer order`); continue; }
    }
    for (const file of sourceFiles(base)) {
      const rel = path.relative(repo, file);
      const group = path.relative(base, file).split(path.sep)[0];
      if (!tree.order.includes(group)) continue;
      checkFile(file, rel, tree.order.indexOf(group), tree, problems);
    }
    for (const dir of tree.above)
      for (const file of sourceFiles(path.join(repo, dir)))
        checkFile(file, path.relative(repo, file), Infinity, tree, problems);
  }
  return problems;
}

// Copies the two trees, adds one upward include to a file of the lowest group of each, and
// expects the check to name exactly those files; then expects the unbroken copy to pass.
function selftest(repo) {
  const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'layers-'));
  try {
    for (const tree of TREES) {
      fs.cpSync(path.join(repo, tree.root), path.join(tmp, tree.root), { recursive: true });
      for (const dir of tree.above)
        fs.cpSync(path.join(repo, dir), path.join(tmp, dir), { recursive: true });
    }
    const clean = check(tmp);
    if (clean.length) throw new Error(`the unbroken copy fails:\n${clean.join('\n')}`);
    const broken = [];
    for (const tree of TREES) {
      const low = path.join(tmp, tree.root, tree.order.find((g) => fs.existsSync(path.join(tmp, tree.root, g))));
      const victim = sourceFiles(low)[0];
      const top = tree.order[tree.order.length - 1];
      fs.appendFileSync(victim, `\n#include "${top}/anything.h"\n`);
      broken.push(path.relative(tmp, victim));
    }
    const found = check(tmp);
    for (const rel of broken)
      if (!found.some((p) => p.startsWith(`${rel}:`)))
        throw new Error(`an upward include in ${rel} passed the check`);
    if (found.length !== broken.length) throw new Error(`unexpected findings:\n${found.join('\n')}`);
    console.log(`selftest: the check caught ${broken.length} deliberate upward includes:\n${found.join('\n')}`);
  } finally {
    fs.rmSync(tmp, { recursive: true, force: true });
  }
}

const args = process.argv.slice(2);
const rootAt = args.indexOf('--root');
const repo = path.resolve(rootAt >= 0 ? args[rootAt + 1] : path.join(path.dirname(new URL(import.meta.url).pathname), '../..'));
if (args.includes('--selftest')) {
  try { selftest(repo); } catch (e) { console.error(`selftest failed: ${e.message}`); process.exit(1); }
} else {
  const problems = check(repo);
  for (const p of problems) console.error(p);
  console.log(problems.length ? `${problems.length} include-direction violations` : 'include directions: ok');
  process.exit(problems.length ? 1 : 0);
}
