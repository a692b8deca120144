// Static checks of the browser UI's sources (plain node, no browser). Registered in CTest as
// `web_static` (tests/CMakeLists.txt):
//   node tests/web/static_checks.mjs --root SOURCE_DIR    the self-test, then web/src
//   node tests/web/static_checks.mjs --selftest           the self-test only
// The rules (docs/design.md sections 2 and 4.6):
//   - only web/src/scene-commands.js calls api.patchScene (api.js defines it);
//   - only web/src/state.js assigns into state.scene (everyone else goes through set());
//   - only web/src/api.js touches the network (fetch, XMLHttpRequest, EventSource, WebSocket,
//     navigator.sendBeacon);
//   - no function is longer than MAX_LINES lines, from its opening line to its closing brace.
// The sources are read by a small tokenizer that knows comments, strings, template literals
// and regular expression literals, so a brace or a name inside one of them counts for nothing.
// Exit 0 pass, 1 fail.
import { readFileSync, readdirSync, statSync } from 'node:fs';
import { join, relative, resolve } from 'node:path';
import { pathToFileURL } from 'node:url';

export const MAX_LINES = 120;
const COMMANDS = 'scene-commands.js';
const STATE = 'state.js';
const API = 'api.js';

// ---- tokenizer ----
// After these tokens a `/` starts a regular expression; after any other it divides.
const BEFORE_REGEX = new Set(['(', ',', '=', ':', '[', '!', '&', '|', '?', '{', '}', ';', '+', '-', '*', '%', '<', '>', '~', '^',
  '=>', '==', '===', '!=', '!==', '<=', '>=', '&&', '||', '??', '+=', '-=', '*=', '/=', '%=', '&=', '|=', '^=', '**',
  'return', 'typeof', 'case', 'do', 'else', 'in', 'of', 'new', 'delete', 'void', 'throw', 'instanceof', 'yield', 'await']);
const PUNCT = ['>>>=', '...', '===', '!==', '**=', '<<=', '>>=', '>>>', '&&=', '||=', '??=', '=>', '==', '!=', '<=', '>=', '&&', '||',
  '??', '?.', '++', '--', '+=', '-=', '*=', '/=', '%=', '&=', '|=', '^=', '**', '<<', '>>'];

/**
 * The tokens of a JavaScript module ({type: name|num|punct|str|regex, value, line}, comments
 * left out; a template literal is a `str` token per piece of text and the tokens of its
 * substitutions), and `blank`: the source with comments and the text of strings, templates
 * and regular expressions replaced by spaces (line breaks kept), for searching code only.
 */
export function tokenize(src) {
  const tokens = [];
  const blank = src.split('');
  let i = 0, line = 1;
  const braces = [];   // per open `{`: true where it opened a template substitution
  const wipe = (from, to) => { for (let k = from; k < to; ++k) if (blank[k] !== '\n') blank[k] = ' '; };
  const countLines = (from, to) => { for (let k = from; k < to; ++k) if (src[k] === '\n') ++line; };
  const push = (type, value, at) => tokens.push({ type, value, line: at });
  const prev = () => tokens.at(-1);
  const regexAllowed = () => {
    const p = prev();
    return !p || (p.type === 'punct' ? BEFORE_REGEX.has(p.value) : p.type === 'name' && BEFORE_REGEX.has(p.value));
  };
  // A template's text from i (just after ` or a substitution's }) to its end or next ${.
  const templateText = () => {
    const start = i, at = line;
    for (;;) {
      if (i >= src.length) throw new Error(`line ${at}: unterminated template literal`);
      const c = src[i];
      if (c === '\\') { i += 2; continue; }
      if (c === '`') { wipe(start, i); countLines(start, i); push('str', src.slice(start, i), at); ++i; return; }
      if (c === '$' && src[i + 1] === '{') {
        wipe(start, i); countLines(start, i); push('str', src.slice(start, i), at);
        i += 2; braces.push(true); push('punct', '${', line); return;
      }
      ++i;
    }
  };
  while (i < src.length) {
    const c = src[i];
    if (c === '\n') { ++line; ++i; continue; }
    if (/\s/.test(c)) { ++i; continue; }
    if (c === '/' && src[i + 1] === '/') {
      const end = src.indexOf('\n', i);
      const to = end < 0 ? src.length : end;
      wipe(i, to); i = to; continue;
    }
    if (c === '/' && src[i + 1] === '*') {
      const end = src.indexOf('*/', i + 2);
      if (end < 0) throw new Error(`line ${line}: unterminated comment`);
      wipe(i, end + 2); countLines(i, end + 2); i = end + 2; continue;
    }
    if (c === '"' || c === "'") {
      const start = i, at = line;
      for (++i; src[i] !== c; ++i) {
        if (i >= src.length || src[i] === '\n') throw new Error(`line ${at}: unterminated string`);
        if (src[i] === '\\') ++i;
      }
      ++i; wipe(start + 1, i - 1); countLines(start, i); push('str', src.slice(start, i), at); continue;
    }
    if (c === '`') { ++i; templateText(); continue; }
    if (c === '/' && regexAllowed()) {
      const start = i, at = line;
      let inClass = false;
      for (++i; inClass || src[i] !== '/'; ++i) {
        if (i >= src.length || src[i] === '\n') throw new Error(`line ${at}: unterminated regular expression`);
        if (src[i] === '\\') ++i;
        else if (src[i] === '[') inClass = true;
        else if (src[i] === ']') inClass = false;
      }
      for (++i; /[a-z]/i.test(src[i] || ''); ++i);
      wipe(start + 1, i); push('regex', src.slice(start, i), at); continue;
    }
    if (/[A-Za-z_$]/.test(c)) {
      const m = /^[A-Za-z0-9_$]+/.exec(src.slice(i, i + 200));
      push('name', m[0], line); i += m[0].length; continue;
    }
    if (/[0-9]/.test(c) || (c === '.' && /[0-9]/.test(src[i + 1]))) {
      const m = /^(0[xXbBoO][0-9a-fA-F_]+n?|[0-9_]*\.?[0-9_]*(e[+-]?[0-9]+)?n?)/.exec(src.slice(i, i + 100));
      push('num', m[0], line); i += m[0].length; continue;
    }
    if (c === '{') { braces.push(false); push('punct', '{', line); ++i; continue; }
    if (c === '}') {
      if (braces.pop()) { push('punct', '}', line); ++i; templateText(); continue; }
      push('punct', '}', line); ++i; continue;
    }
    const p = PUNCT.find((x) => src.startsWith(x, i)) || c;
    push('punct', p, line); i += p.length;
  }
  return { tokens, blank: blank.join('') };
}

// ---- functions and their lengths ----
const CONTROL = new Set(['if', 'for', 'while', 'switch', 'catch', 'with']);
const OPEN = { '(': ')', '[': ']', '{': '}', '${': '}' };

/** For each opening bracket token, the index of its closing one (and back). */
function matchBrackets(tokens) {
  const match = new Map();
  const stack = [];
  tokens.forEach((t, k) => {
    if (t.type !== 'punct') return;
    if (OPEN[t.value]) stack.push(k);
    else if (t.value === ')' || t.value === ']' || t.value === '}') {
      const o = stack.pop();
      if (o === undefined) throw new Error(`line ${t.line}: unbalanced ${t.value}`);
      match.set(o, k); match.set(k, o);
    }
  });
  if (stack.length) throw new Error(`line ${tokens[stack.at(-1)].line}: unclosed ${tokens[stack.at(-1)].value}`);
  return match;
}

/** Where a function that begins just before token k begins: its name, `function`, `async`. */
function startOf(tokens, k) {
  let s = k;
  while (s > 0 && ['function', 'async', 'get', 'set', 'static', '*'].includes(tokens[s - 1].value) && tokens[s - 1].type !== 'str') --s;
  return tokens[s].line;
}

/**
 * Every function of a module: {name, start, end, lines}. A body is a `{` after `=>`, or after
 * the parameter list of a `function`, a named function or a method; an arrow without braces
 * ends where its expression does.
 */
export function functions(src) {
  const { tokens } = tokenize(src);
  const match = matchBrackets(tokens);
  const out = [];
  const isP = (t, v) => t && t.type === 'punct' && t.value === v;
  tokens.forEach((t, k) => {
    if (isP(t, '=>')) {
      const before = tokens[k - 1];
      const first = isP(before, ')') ? match.get(k - 1) : k - 1;
      const start = startOf(tokens, first);
      const q = tokens[first - 1]?.value === 'async' ? first - 2 : first - 1;
      const name = isP(tokens[q], '=') && tokens[q - 1]?.type === 'name' ? tokens[q - 1].value : '(arrow)';
      let end;
      if (isP(tokens[k + 1], '{')) end = tokens[match.get(k + 1)].line;
      else {
        let e = k + 1;   // an expression body: up to a , ; or closing bracket at its own depth
        for (; e < tokens.length; ++e) {
          const x = tokens[e];
          if (x.type === 'punct' && OPEN[x.value]) { e = match.get(e); continue; }
          if (x.type === 'punct' && [',', ';', ')', ']', '}'].includes(x.value)) break;
        }
        end = tokens[e - 1].line;
      }
      out.push({ name, start, end, lines: end - start + 1 });
      return;
    }
    if (!isP(t, '{') || !isP(tokens[k - 1], ')')) return;
    const open = match.get(k - 1);
    const head = tokens[open - 1];
    // name(...) { is a function (a declaration, a named expression or a method) unless name is
    // a control keyword; `class X extends f(a) {` opens a class body.
    if (!head || !(head.type === 'name' || isP(head, '*'))) return;
    if (CONTROL.has(head.value) || tokens[open - 2]?.value === 'extends') return;
    const start = startOf(tokens, open - 1);
    const end = tokens[match.get(k)].line;
    out.push({ name: head.type === 'name' && head.value !== 'function' ? head.value : '(function)', start, end, lines: end - start + 1 });
  });
  return out;
}

// ---- the rules ----
const NETWORK = /\b(fetch\s*\(|XMLHttpRequest\b|EventSource\b|WebSocket\b|sendBeacon\b)/;
// state.scene, then members (.name, [expr]), then an assignment (not == or ===, not =>), or
// ++/--, or delete; Object.assign into it; an array method that changes it in place.
const SCENE_WRITE = new RegExp([
  String.raw`\bstate\s*\.\s*scene(\s*(\.\s*[\w$]+|\[[^\]]*\]))*\s*(=(?![=>])|[-+*/%&|^]=|\*\*=|<<=|>>>?=|&&=|\|\|=|\?\?=|\+\+|--)`,
  String.raw`(\+\+|--|\bdelete)\s*state\s*\.\s*scene\b`,
  String.raw`\bObject\s*\.\s*(assign|defineProperty|defineProperties)\s*\(\s*state\s*\.\s*scene\b`,
  // An array of it changed in place.
  String.raw`\bstate\s*\.\s*scene(\s*(\.\s*[\w$]+|\[[^\]]*\]))*\s*\.\s*(push|pop|shift|unshift|splice|sort|reverse|fill|copyWithin)\s*\(`,
].join('|'));

const lineAt = (text, index) => text.slice(0, index).split('\n').length;

/** The rule breaches of one module (`file`: its path under web/src, with / separators). */
export function checkModule(file, src) {
  const problems = [];
  let blank, fns;
  try {
    ({ blank } = tokenize(src));
    fns = functions(src);
  } catch (e) {
    return [`${file}: cannot read: ${e.message}`];
  }
  const base = file.split('/').pop();
  const find = (re, what) => {
    const g = new RegExp(re.source, 'g');
    for (const m of blank.matchAll(g)) problems.push(`${file}:${lineAt(blank, m.index)}: ${what}`);
  };
  if (base !== COMMANDS && base !== API) find(/\bpatchScene\b/, 'patchScene outside scene-commands.js (edit the scene through it)');
  if (base === API) {
    for (const m of blank.matchAll(/\bpatchScene\b/g)) {
      if (!/export\s+const\s+$/.test(blank.slice(Math.max(0, m.index - 40), m.index))) {
        problems.push(`${file}:${lineAt(blank, m.index)}: patchScene used inside api.js`);
      }
    }
  }
  if (base !== STATE) find(SCENE_WRITE, 'assigns into state.scene (only set() in state.js may)');
  if (base !== API) find(NETWORK, 'network access outside api.js');
  for (const f of fns) {
    if (f.lines > MAX_LINES) problems.push(`${file}:${f.start}: function ${f.name} is ${f.lines} lines (at most ${MAX_LINES})`);
  }
  return problems;
}

function jsFiles(dir) {
  return readdirSync(dir).flatMap((n) => {
    const p = join(dir, n);
    if (statSync(p).isDirectory()) return jsFiles(p);
    return n.endsWith('.js') ? [p] : [];
  });
}

/** The breaches of every module under `srcDir`. */
export function checkTree(srcDir) {
  const files = jsFiles(srcDir);
  if (!files.some((f) => f.endsWith(COMMANDS))) return [`${COMMANDS} is missing from ${srcDir}`];
  return files.flatMap((f) => checkModule(relative(srcDir, f).split('\\').join('/'), readFileSync(f, 'utf8')));
}

// ---- self-test: each rule fails on a deliberate breach, and nothing fails on clean code ----
function selftest() {
  // A function of MAX_LINES + 1 lines from its head line to its closing line.
  const long = (head, tail = '}') => `${head}\n${'  x();\n'.repeat(MAX_LINES - 1)}${tail}\n`;
  const cases = [
    // [file, source, expected substring of a problem or null for none]
    ['panels/a.js', `import * as api from '../api.js';\napi.patchScene(s, {});\n`, 'patchScene outside'],
    ['panels/a.js', `const f = api.patchScene;\n`, 'patchScene outside'],
    ['scene-commands.js', `api.patchScene(s, p);\n`, null],
    ['api.js', `export const patchScene = (s, p) => request('PATCH', s, p);\n`, null],
    ['api.js', `export const patchScene = (s, p) => 1;\nfunction g() { return patchScene(1, 2); }\n`, 'used inside api.js'],
    ['panels/a.js', `// api.patchScene(s, {}) in a comment\nconst t = 'patchScene(';\nconst u = \`patchScene\`;\n`, null],
    ['panels/a.js', `state.scene.objects = all;\n`, 'assigns into state.scene'],
    ['panels/a.js', `state.scene.objects[index].params = params;\n`, 'assigns into state.scene'],
    ['panels/a.js', `state.scene = s;\n`, 'assigns into state.scene'],
    ['panels/a.js', `state.scene.render['width'] += 2;\n`, 'assigns into state.scene'],
    ['panels/a.js', `delete state.scene.notes;\n`, 'assigns into state.scene'],
    ['panels/a.js', `Object.assign(state.scene, x);\n`, 'assigns into state.scene'],
    ['panels/a.js', `state.scene.objects.push(o);\n`, 'assigns into state.scene'],
    ['panels/a.js', `state.scene.objects[i].textures.splice(0, 1);\n`, 'assigns into state.scene'],
    ['panels/a.js', `const all = state.scene.objects.map((o) => o);\nall.push(1);\n`, null],
    ['panels/a.js', `if (state.scene.objects === x || state.scene == y) f(state.scene);\nconst g = (state) => state.scene;\n`, null],
    ['state.js', `export function set(c) { Object.assign(state, c); state.scene = c.scene; }\n`, null],
    ['panels/a.js', `fetch('/api/health');\n`, 'network access'],
    ['panels/a.js', `const ws = new WebSocket(u);\n`, 'network access'],
    ['panels/a.js', `const x = new XMLHttpRequest();\n`, 'network access'],
    ['panels/a.js', `navigator.sendBeacon(u);\n`, 'network access'],
    ['api.js', `const r = await fetch(p);\n`, null],
    ['panels/a.js', `// fetch(x) in a comment\nconst s = "fetch(";\n`, null],
    ['panels/a.js', long('export function mountBig(el) {'), 'function mountBig is 121 lines'],
    ['panels/a.js', long('const f = async (el) => {'), 'function f is 121 lines'],
    ['panels/a.js', `const o = {\n${long('  async method(a, b) {', '  },')}};\n`, 'function method is 121 lines'],
    ['panels/a.js', `class C {\n${long('  static run() {', '  }')}}\n`, 'function run is 121 lines'],
    ['panels/a.js', long("on('x', function () {", '});'), 'function (function) is 121 lines'],
    ['panels/a.js', `function ok() {\n${'  x();\n'.repeat(MAX_LINES - 2)}}\n`, null],
    ['panels/a.js', `if (a) {\n${'  x();\n'.repeat(MAX_LINES + 5)}}\n`, null],
    ['panels/a.js', `const f = (x) => ({\n${'  a: 1,\n'.repeat(MAX_LINES)}});\n`, 'function f is'],
    // Braces in strings, templates, regular expressions and comments count for nothing: each
    // of these would otherwise unbalance the function or end it early.
    ['panels/a.js', `function g() {\n  const s = '}';\n  const t = \`\${'{'} \${a ? \`}\` : b} }\`;\n  const r = /[}/]\\}/g;\n  // }\n  /* } */\n  return s / 2 / 3;\n}\n${long('function h() {')}`, 'function h is 121 lines'],
  ];
  let failed = 0;
  for (const [file, src, want] of cases) {
    const got = checkModule(file, src);
    const pass = want === null ? got.length === 0 : got.some((p) => p.includes(want));
    if (!pass) {
      failed++;
      console.log(`selftest FAIL ${file} (${want ?? 'no problem'}): got ${JSON.stringify(got)}\n--- source:\n${src.slice(0, 300)}`);
    }
  }
  console.log(`selftest: ${cases.length - failed}/${cases.length} cases as expected`);
  return failed;
}

function main() {
  const a = process.argv.slice(2);
  let failed = selftest();
  if (a.includes('--selftest')) process.exit(failed ? 1 : 0);
  const r = a.indexOf('--root');
  const root = resolve(r >= 0 ? a[r + 1] : process.env.BRDFA_ROOT || '.');
  const problems = checkTree(join(root, 'web', 'src'));
  for (const p of problems) console.log(`FAIL web/src/${p}`);
  failed += problems.length;
  console.log(failed ? `${failed} problem(s)` : 'web/src: all static checks passed');
  process.exit(failed ? 1 : 0);
}

if (import.meta.url === pathToFileURL(process.argv[1]).href) main();
