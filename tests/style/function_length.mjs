#!/usr/bin/env node
// No C++ function in renderer/, server/ or bench/ is longer than 120 lines, counted from the line
// of its opening brace to its closing brace, lambdas inside it included. A function that must
// stay longer says why in a comment containing "long-function:" on one of the three lines above
// its opening brace. (web/src is checked by tests/web/static_checks.mjs.)
//
//   node tests/style/function_length.mjs --root <repo> [--max 120]
//   node tests/style/function_length.mjs --selftest
import fs from 'node:fs';
import path from 'node:path';

const DIRS = ['renderer', 'server', 'bench'];

// Blanks comments, string and character literals (raw strings too), keeping every newline, so
// braces inside them do not count.
export function stripCxx(src) {
  let out = '';
  let i = 0;
  const blank = (s) => s.replace(/[^\n]/g, ' ');
  while (i < src.length) {
    const c = src[i];
    if (src.startsWith('//', i)) {
      let j = src.indexOf('\n', i); if (j < 0) j = src.length;
      out += blank(src.slice(i, j)); i = j;
    } else if (src.startsWith('/*', i)) {
      let j = src.indexOf('*/', i + 2); j = j < 0 ? src.length : j + 2;
      out += blank(src.slice(i, j)); i = j;
    } else if (c === 'R' && src[i + 1] === '"' && !/[\w]/.test(src[i - 1] ?? '')) {
      const m = /^R"([^(\s]*)\(/.exec(src.slice(i));
      const end = src.indexOf(`)${m[1]}"`, i);
      const j = end < 0 ? src.length : end + m[1].length + 2;
      out += blank(src.slice(i, j)); i = j;
    } else if (c === '"' || (c === "'" && !/[0-9a-fA-F]/.test(src[i - 1] ?? ''))) {
      let j = i + 1;
      while (j < src.length && src[j] !== c && src[j] !== '\n') j += src[j] === '\\' ? 2 : 1;
      out += blank(src.slice(i, j + 1)); i = j + 1;
    } else { out += c; i += 1; }
  }
  return out;
}

// Each function body at namespace or class scope: { line, lines }.
export function functionBodies(src) {
  const s = stripCxx(src);
  const stack = [];
  const found = [];
  const lineAt = (p) => s.slice(0, p).split('\n').length;
  for (let p = 0; p < s.length; p++) {
    if (s[p] === '{') {
      const head = s.slice(Math.max(0, p - 400), p);
      let kind = 'block';
      if (stack.some((k) => k.kind === 'func')) kind = 'block';
      else if (/\b(namespace|class|struct|union|enum)\b[^;{}()]*$/.test(head)) kind = 'scope';
      else if (/(\)|\bconst|\bnoexcept|\boverride|\bfinal|->\s*[\w:<>,\s*&]+)\s*$/.test(head) ||
               /\)\s*:\s*[^;{}]*[)}]\s*$/.test(head)) kind = /=\s*$/.test(head) ? 'block' : 'func';
      stack.push({ kind, p });
    } else if (s[p] === '}') {
      const open = stack.pop();
      if (open?.kind === 'func') {
        const line = lineAt(open.p);
        found.push({ line, lines: lineAt(p) - line + 1 });
      }
    }
  }
  return found;
}

function sources(dir) {
  if (!fs.existsSync(dir)) return [];
  return fs.readdirSync(dir, { withFileTypes: true }).flatMap((e) => {
    const p = path.join(dir, e.name);
    if (e.isDirectory()) return sources(p);
    return /\.(h|hpp|cpp|cc)$/.test(e.name) ? [p] : [];
  });
}

export function check(repo, max) {
  const long = [];
  for (const dir of DIRS)
    for (const file of sources(path.join(repo, dir))) {
      const src = fs.readFileSync(file, 'utf8');
      const lines = src.split('\n');
      for (const f of functionBodies(src)) {
        if (f.lines <= max) continue;
        const above = lines.slice(Math.max(0, f.line - 4), f.line).join('\n');
        if (!above.includes('long-function:'))
          long.push(`${path.relative(repo, file)}:${f.line}: a function of ${f.lines} lines (at most ${max})`);
      }
    }
  return long;
}

function selftest() {
  const body = (n) => Array.from({ length: n }, (_, i) => `  x += ${i}; // "}" '{'`).join('\n');
  const cases = [
    [`int f(int x) {\n${body(130)}\n  return x;\n}\n`, [132 + 1]],
    [`namespace a {\nstruct S {\n  void g() const {\n${body(10)}\n  }\n};\n}\n`, [12]],
    [`auto h = [](int x) {\n${body(3)}\n};\nvoid k() { auto q = [] { return 1; }; }\n`, [5, 1]],
  ];
  for (const [src, want] of cases) {
    const got = functionBodies(src).map((f) => f.lines);
    if (JSON.stringify(got) !== JSON.stringify(want)) throw new Error(`measured ${got}, expected ${want}`);
  }
  console.log('selftest: function lengths measured as expected');
}

const args = process.argv.slice(2);
const opt = (name, dflt) => (args.includes(name) ? args[args.indexOf(name) + 1] : dflt);
if (args.includes('--selftest')) {
  try { selftest(); } catch (e) { console.error(`selftest failed: ${e.message}`); process.exit(1); }
} else {
  const repo = path.resolve(opt('--root', path.join(path.dirname(new URL(import.meta.url).pathname), '../..')));
  const long = check(repo, Number(opt('--max', 120)));
  for (const l of long) console.error(l);
  console.log(long.length ? `${long.length} functions too long` : 'function lengths: ok');
  process.exit(long.length ? 1 : 0);
}
