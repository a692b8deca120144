// Checks docker/Dockerfile without a container engine (ctest deploy_dockerfile):
//   a. it has named stages, and the build stage's `make` commands, dry-run (`make -n -B`) in the
//      repository, install the build-only dependencies, bundle the UI (npm ci, web/build.mjs) and
//      configure + build with cmake; that configuration, made for real in a scratch folder, puts
//      the server and both workers in the default target, at the paths the runtime stage copies;
//   b. the runtime stage installs no toolchain or -dev package (its apt-get install is simulated
//      against the base image's packages, dependencies included) and copies no source folder;
//   c. every shared library `ldd` finds for the binaries belongs (`dpkg -S`) to a package of that
//      simulated runtime image;
//   d. the runtime stage's file system, rebuilt in a temporary folder from its COPY lines (the
//      build stage's WORKDIR maps to --root, its build folder to --build) and its RUN mkdir/chown,
//      serves the UI: the server starts exactly as ENTRYPOINT + CMD say (paths moved into the
//      folder, the port a free loopback one, --host 127.0.0.1), as the image's USER when this runs
//      as root; GET / is the page with dist/main.js, every file the page names is there, the
//      workers run from the image's folder, the HEALTHCHECK passes (and fails on a closed port);
//   e. HEALTHCHECK, a non-root USER, VOLUME /data as the data folder, EXPOSE, STOPSIGNAL, ENV.
//
//   node tests/deploy/dockerfile.mjs --root SOURCE_DIR --build BUILD_DIR [--dockerfile F] [--keep]
//
// Exit 0: every check passed; 1: one failed; 77: skipped (no dpkg, apt lists, make or cmake here,
// or --build is a sanitizer build).
import { spawn, spawnSync } from 'node:child_process';
import crypto from 'node:crypto';
import fs from 'node:fs';
import http from 'node:http';
import net from 'node:net';
import os from 'node:os';
import path from 'node:path';

const argv = process.argv.slice(2);
const opt = (name, dflt) => {
  const i = argv.indexOf(name);
  return i >= 0 && i + 1 < argv.length ? argv[i + 1] : dflt;
};
const root = path.resolve(opt('--root', path.join(path.dirname(new URL(import.meta.url).pathname), '../..')));
const build = path.resolve(opt('--build', path.join(root, 'build')));
const dockerfile = path.resolve(root, opt('--dockerfile', 'docker/Dockerfile'));
const keep = argv.includes('--keep');

const WORKERS = ['brdfa-render-worker', 'brdfa-compile-worker'];
const BINARIES = ['brdfa-server', ...WORKERS];

// ---------------------------------------------------------------------------------------------
// Results: one row per check, printed as a table at the end.
const rows = [];
let failed = 0;
function record(section, what, ok, detail = '') {
  rows.push([section, what, ok ? 'ok' : 'FAIL', detail]);
  if (!ok) failed++;
  return ok;
}
class Fatal extends Error {}
function need(section, what, ok, detail) {
  if (!record(section, what, ok, detail)) throw new Fatal(`${what}: ${detail}`);
}
function printTable() {
  rows.sort((x, y) => x[0].localeCompare(y[0]));  // stable: sections in order, checks as run
  const widths = [0, 1, 2].map((c) => Math.max(...rows.map((r) => r[c].length)));
  const line = (r) => r.map((v, c) => (c < 3 ? v.padEnd(widths[c]) : v)).join('  ');
  console.log(line(['', 'check', 'result', 'detail']));
  for (const r of rows) console.log(line(r));
  console.log(failed ? `\n${failed} check(s) FAILED` : `\nall ${rows.filter((r) => r[2] === 'ok').length} checks passed`);
}

const has = (cmd) => spawnSync('sh', ['-c', `command -v ${cmd}`], { encoding: 'utf8' }).status === 0;
function run(cmd, args, options = {}) {
  const r = spawnSync(cmd, args, { encoding: 'utf8', maxBuffer: 64 << 20, ...options });
  if (r.error) throw r.error;
  return r;
}
// A clean environment, as in an image build: nothing of ours (MAKEFLAGS, BUILD=...) leaks in.
const cleanEnv = { PATH: '/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin', HOME: os.tmpdir(), LANG: 'C' };

// ---------------------------------------------------------------------------------------------
// Dockerfile parsing: logical lines (comments dropped, continuations joined), instructions,
// stages; and a small POSIX shell word splitter for RUN lines.
function parseDockerfile(text) {
  const instrs = [];
  let cur = null;
  let start = 0;
  text.split('\n').forEach((raw, i) => {
    if (/^\s*#/.test(raw)) return;             // a comment, also inside a continuation
    if (cur === null) {
      if (!raw.trim()) return;
      cur = '';
      start = i + 1;
    }
    if (/\\\s*$/.test(raw)) {
      cur += raw.replace(/\\\s*$/, '') + ' ';
      return;
    }
    cur += raw;
    const m = cur.trim().match(/^(\S+)\s*([\s\S]*)$/);
    instrs.push({ kw: m[1].toUpperCase(), rest: m[2].trim(), line: start });
    cur = null;
  });
  const stages = [];
  for (const ins of instrs) {
    if (ins.kw === 'FROM') {
      const words = ins.rest.split(/\s+/).filter((w) => !w.startsWith('--'));
      const asAt = words.findIndex((w) => w.toUpperCase() === 'AS');
      stages.push({ base: words[0], name: asAt >= 0 ? words[asAt + 1] : null, line: ins.line, instrs: [] });
    } else if (stages.length) {
      stages.at(-1).instrs.push(ins);
    } else if (ins.kw !== 'ARG') {
      throw new Error(`line ${ins.line}: ${ins.kw} before the first FROM`);
    }
  }
  return stages;
}

// Words of a shell command line, split into simple commands at && || ; | (quotes removed).
function shellCommands(s) {
  const cmds = [[]];
  let w = null;
  const push = () => {
    if (w !== null) cmds.at(-1).push(w);
    w = null;
  };
  for (let i = 0; i < s.length;) {
    const c = s[i];
    if (c === "'") {
      const j = s.indexOf("'", i + 1);
      if (j < 0) throw new Error(`unterminated ' in: ${s}`);
      w = (w ?? '') + s.slice(i + 1, j);
      i = j + 1;
    } else if (c === '"') {
      let v = '';
      for (i++; i < s.length && s[i] !== '"'; i++) {
        if (s[i] === '\\' && '"\\$`'.includes(s[i + 1])) i++;
        v += s[i];
      }
      if (i >= s.length) throw new Error(`unterminated " in: ${s}`);
      w = (w ?? '') + v;
      i++;
    } else if (c === '\\') {
      w = (w ?? '') + (s[i + 1] ?? '');
      i += 2;
    } else if (/\s/.test(c)) {
      push();
      i++;
    } else if ((c === '&' && s[i + 1] === '&') || (c === '|' && s[i + 1] === '|')) {
      push();
      cmds.push([]);
      i += 2;
    } else if (c === ';' || c === '|') {
      push();
      cmds.push([]);
      i++;
    } else {
      w = (w ?? '') + c;
      i++;
    }
  }
  push();
  // Leading VAR=value assignments are the command's environment, not the command.
  return cmds.map((words) => words.slice(words.findIndex((x) => !/^[A-Za-z_][A-Za-z0-9_]*=/.test(x)))).filter((c) => c.length);
}

function execForm(ins) {
  if (ins.rest.startsWith('[')) return { exec: true, argv: JSON.parse(ins.rest) };
  return { exec: false, argv: ['/bin/sh', '-c', ins.rest] };
}
function parseCopy(rest) {
  const flags = {};
  let r = rest;
  for (let m; (m = r.match(/^--([\w-]+)(?:=(\S+))?\s*/));) {
    flags[m[1]] = m[2] ?? true;
    r = r.slice(m[0].length);
  }
  const parts = r.startsWith('[') ? JSON.parse(r) : r.split(/\s+/);
  return { flags, srcs: parts.slice(0, -1), dest: parts.at(-1) };
}
function parseEnv(rest) {
  const env = {};
  const words = shellCommands(rest)[0] ?? [];
  if (words.length === 2 && !words[0].includes('=')) env[words[0]] = words[1];  // ENV KEY value
  else for (const w of words) env[w.slice(0, w.indexOf('='))] = w.slice(w.indexOf('=') + 1);
  return env;
}

// ---------------------------------------------------------------------------------------------
// Debian helpers: the package of a file, and a simulated `apt-get install` on a base image.
function packagesOf(file) {
  const candidates = [file, fs.realpathSync(file)];
  for (const f of [...candidates]) {
    if (f.startsWith('/usr/lib/')) candidates.push(f.slice(4));
    else if (f.startsWith('/lib/') || f.startsWith('/lib64/')) candidates.push('/usr' + f);
  }
  for (const f of candidates) {
    const r = run('dpkg', ['-S', f]);
    if (r.status === 0) {
      const line = r.stdout.split('\n').find((l) => l.includes(': '));
      return line.slice(0, line.indexOf(': ')).split(', ').map((p) => p.replace(/:.*$/, ''));
    }
  }
  return [];
}

// The packages of the base image (debian:12-slim: the required and essential ones and apt, with
// their dependencies), approximated by this machine's installed versions of them.
function basePackages() {
  const q = run('dpkg-query', ['-W', '-f=${Package} ${Priority} ${Essential}\n']);
  const seed = q.stdout.split('\n').map((l) => l.split(' ')).filter((f) => f[1] === 'required' || f[2] === 'yes').map((f) => f[0]);
  seed.push('apt');
  const d = run('apt-cache', ['depends', '--recurse', '--installed', '--no-recommends', '--no-suggests', '--no-conflicts',
    '--no-breaks', '--no-replaces', '--no-enhances', ...seed]);
  const set = new Set(d.stdout.split('\n').filter((l) => l && !l.startsWith(' ') && !l.startsWith('<')).map((l) => l.replace(/:.*$/, '')));
  return [...set].filter((p) => run('dpkg-query', ['-W', '-f=${Status}', p]).stdout.includes('install ok installed'));
}

// What `apt-get install --no-install-recommends pkgs` adds to an image holding only `base`:
// apt's own resolver, run in simulation against a status file of just those packages.
function simulateInstall(base, pkgs, flags, tmp) {
  const status = path.join(tmp, 'base-status');
  fs.writeFileSync(status, run('dpkg-query', ['-s', ...base]).stdout);
  const r = run('apt-get', ['install', '-s', '-o', `Dir::State::status=${status}`, '-o', 'Debug::NoLocking=1',
    '-o', 'Dir::Cache::pkgcache=', '-o', 'Dir::Cache::srcpkgcache=', ...flags, ...pkgs], { env: cleanEnv });
  if (r.status !== 0) throw new Error(`apt-get install -s failed (apt metadata missing? run apt-get update):\n${r.stdout}${r.stderr}`);
  return r.stdout.split('\n').filter((l) => l.startsWith('Inst ')).map((l) => l.split(' ')[1].replace(/:.*$/, ''));
}

// ---------------------------------------------------------------------------------------------
function httpGet(port, urlPath, headers = {}) {
  return new Promise((resolve, reject) => {
    const req = http.get({ host: '127.0.0.1', port, path: urlPath, headers, timeout: 30000 }, (res) => {
      const chunks = [];
      res.on('data', (c) => chunks.push(c));
      res.on('end', () => resolve({ status: res.statusCode, headers: res.headers, body: Buffer.concat(chunks) }));
    });
    req.on('timeout', () => req.destroy(new Error(`GET ${urlPath}: timeout`)));
    req.on('error', reject);
  });
}
function httpPost(port, urlPath, body) {
  return new Promise((resolve, reject) => {
    const req = http.request({ host: '127.0.0.1', port, path: urlPath, method: 'POST', timeout: 60000,
      headers: { 'Content-Length': Buffer.byteLength(body) } }, (res) => {
      const chunks = [];
      res.on('data', (c) => chunks.push(c));
      res.on('end', () => resolve({ status: res.statusCode, body: Buffer.concat(chunks) }));
    });
    req.on('timeout', () => req.destroy(new Error(`POST ${urlPath}: timeout`)));
    req.on('error', reject);
    req.end(body);
  });
}
function freePort() {
  return new Promise((resolve, reject) => {
    const s = net.createServer();
    s.on('error', reject);
    s.listen(0, '127.0.0.1', () => {
      const { port } = s.address();
      s.close(() => resolve(port));
    });
  });
}
function descendants(pid) {
  const out = [];
  const walk = (p) => {
    let tasks = [];
    try { tasks = fs.readdirSync(`/proc/${p}/task`); } catch { return; }
    for (const t of tasks) {
      let kids = '';
      try { kids = fs.readFileSync(`/proc/${p}/task/${t}/children`, 'utf8'); } catch { continue; }
      for (const k of kids.split(/\s+/).filter(Boolean).map(Number)) {
        let exe = '?';
        try { exe = fs.readlinkSync(`/proc/${k}/exe`); } catch { /* gone */ }
        out.push({ pid: k, exe });
        walk(k);
      }
    }
  };
  walk(pid);
  return out;
}
function walkFiles(dir, out = []) {
  for (const e of fs.readdirSync(dir, { withFileTypes: true })) {
    const p = path.join(dir, e.name);
    if (e.isDirectory()) walkFiles(p, out);
    else out.push(p);
  }
  return out;
}
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

// ---------------------------------------------------------------------------------------------
async function main() {
  for (const tool of ['dpkg', 'dpkg-query', 'apt-get', 'apt-cache', 'ldd', 'make', 'cmake']) {
    if (!has(tool)) {
      console.log(`SKIP: ${tool} not found; this test needs a Debian machine with the build tools`);
      process.exit(77);
    }
  }
  // The image ships a Release build: a sanitizer build's libraries (libasan, libubsan) and its
  // environment (ASAN_OPTIONS, LD_PRELOAD in make sanitize) are not the image's.
  const cache = path.join(build, 'CMakeCache.txt');
  if (fs.existsSync(cache) && /^BRDFA_SANITIZE:BOOL=ON$/m.test(fs.readFileSync(cache, 'utf8'))) {
    console.log('SKIP: a sanitizer build; the image holds Release binaries');
    process.exit(77);
  }
  if (run('apt-cache', ['show', 'libvulkan1']).status !== 0) {
    console.log('SKIP: no apt package lists here (apt-get update); the runtime packages cannot be resolved');
    process.exit(77);
  }
  const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'brdfa-dockerfile-'));
  fs.chmodSync(tmp, 0o755);
  let server = null;
  try {
    await checks(tmp, (s) => { server = s; });
  } catch (e) {
    if (!(e instanceof Fatal)) record('!', 'unexpected error', false, String(e.stack || e).split('\n').slice(0, 3).join(' | '));
  } finally {
    if (server) await stopServer(server);
    if (keep) console.log(`kept ${tmp}`);
    else fs.rmSync(tmp, { recursive: true, force: true });
  }
  printTable();
  process.exit(failed ? 1 : 0);
}

async function checks(tmp, setServer) {
  // --- a. stages and the build stage's make targets ---------------------------------------
  const stages = parseDockerfile(fs.readFileSync(dockerfile, 'utf8'));
  need('a', 'stages', stages.length >= 2 && stages.every((s) => s.name),
    stages.map((s) => `${s.name ?? '(unnamed)'}=${s.base}`).join(', ') + ' (want >= 2, each FROM ... AS name)');
  const runtime = stages.at(-1);
  const copies = runtime.instrs.filter((i) => i.kw === 'COPY' || i.kw === 'ADD').map((i) => ({ ...parseCopy(i.rest), line: i.line, kw: i.kw }));
  const fromNames = [...new Set(copies.map((c) => c.flags.from).filter(Boolean))];
  need('a', 'runtime copies from a build stage', fromNames.length === 1 && stages.some((s) => s.name === fromNames[0] && s !== runtime),
    `COPY --from=${fromNames.join(',') || '(none)'}`);
  const buildStage = stages.find((s) => s.name === fromNames[0]);
  let workdir = '/';
  for (const i of buildStage.instrs) if (i.kw === 'WORKDIR') workdir = path.posix.resolve(workdir, i.rest);
  const buildCmds = buildStage.instrs.filter((i) => i.kw === 'RUN').flatMap((i) => shellCommands(i.rest));
  const makeCmds = buildCmds.filter((c) => c[0] === 'make');
  need('a', 'build stage runs make', makeCmds.length > 0, `stage ${buildStage.name}: ${makeCmds.map((c) => c.join(' ')).join('; ') || 'no make command'}`);

  // The dry run of each make command, every recipe printed (-B) and none executed (-n).
  const dry = [];
  for (const c of makeCmds) {
    const r = run('make', ['-n', '-B', ...c.slice(1)], { cwd: root, env: cleanEnv });
    need('a', `make -n -B ${c[1]} ...: dry run`, r.status === 0, r.status === 0 ? `${r.stdout.trim().split('\n').length} recipe lines` : r.stderr.trim());
    dry.push(...r.stdout.split('\n').map((l) => l.trim()).filter(Boolean));
  }
  const find = (re) => dry.find((l) => re.test(l));
  const depsLines = [...dry.filter((l) => /install-deps\.sh/.test(l)),
    ...buildCmds.filter((c) => c.some((w) => w.endsWith('install-deps.sh'))).map((c) => c.join(' '))];
  const modes = depsLines.map((l) => (/\s--build\b/.test(l) ? '--build' : 'all'));
  record('a', 'dependencies: install-deps.sh --build', depsLines.length > 0 && modes.every((m) => m === '--build'),
    depsLines.join('; ') || 'install-deps.sh never runs');
  const buildList = run('sh', [path.join(root, 'docker/install-deps.sh'), '--build', '--list']).stdout.split('\n').filter(Boolean);
  record('a', 'the --build set: cmake, node, npm, no browser/tests', ['cmake', 'nodejs', 'npm'].every((p) => buildList.includes(p)) &&
    !buildList.some((p) => /chromium|gtest|mesa-vulkan-drivers/.test(p)), `${buildList.length} packages`);
  record('a', 'web: npm ci', !!find(/\bnpm ci\b/), find(/\bnpm ci\b/) ?? 'missing');
  const bundle = find(/(cd web && node build\.mjs|node (\.\/)?web\/build\.mjs)/);
  record('a', 'web: bundle by web/build.mjs', !!bundle, bundle ?? 'missing');
  const configure = find(/^cmake\s+-S\s+\.\s+-B\s+\S+/);
  need('a', 'cmake configure', !!configure, configure ?? 'missing');
  const cfgWords = shellCommands(configure)[0];
  const buildDir = cfgWords[cfgWords.indexOf('-B') + 1];
  const cfgArgs = cfgWords.filter((w) => w.startsWith('-D'));
  record('a', 'configure: Release, tests and bench off', cfgArgs.includes('-DCMAKE_BUILD_TYPE=Release') &&
    cfgArgs.includes('-DBRDFA_BUILD_TESTS=OFF') && cfgArgs.includes('-DBRDFA_BUILD_BENCH=OFF'), cfgArgs.join(' '));
  const cbuild = find(new RegExp(`^cmake\\s+--build\\s+${buildDir.replace(/[.*+?^${}()|[\]\\]/g, '\\$&')}(\\s|$)`));
  record('a', 'cmake --build, default target', !!cbuild && !/--target|\s-t\s/.test(cbuild), cbuild ?? `no cmake --build ${buildDir}`);
  const order = [bundle, configure, cbuild].map((l) => dry.indexOf(l));
  record('a', 'bundle before the C++ build', order.every((x) => x >= 0) && order[0] < order[2], `dry-run lines ${order.join(', ')}`);

  // That configuration for real, in a scratch folder: which executables the default target
  // builds, and where (the CMake file API and the generated Makefile2).
  const cfgDir = path.join(tmp, 'configure');
  fs.mkdirSync(path.join(cfgDir, '.cmake/api/v1/query'), { recursive: true });
  fs.writeFileSync(path.join(cfgDir, '.cmake/api/v1/query/codemodel-v2'), '');
  const cfg = run('cmake', ['-S', root, '-B', cfgDir, '-G', 'Unix Makefiles', ...cfgArgs], { env: cleanEnv });
  need('a', 'that configure runs', cfg.status === 0, cfg.status === 0 ? `cmake -S <root> -B <scratch> ${cfgArgs.join(' ')}` : cfg.stderr.trim().slice(-300));
  const reply = path.join(cfgDir, '.cmake/api/v1/reply');
  const model = JSON.parse(fs.readFileSync(path.join(reply, fs.readdirSync(reply).find((f) => f.startsWith('codemodel-v2-'))), 'utf8'));
  const makefile2 = fs.readFileSync(path.join(cfgDir, 'CMakeFiles/Makefile2'), 'utf8');
  const inAll = (dir, name) => {
    const d = dir === '.' ? '' : `${dir}/`;
    return new RegExp(`^${d}all: ${d}CMakeFiles/${name}\\.dir/all$`, 'm').test(makefile2) &&
      (dir === '.' || new RegExp(`^all: ${dir}/all$`, 'm').test(makefile2));
  };
  const artifacts = {};
  for (const t of model.configurations[0].targets) {
    if (!BINARIES.includes(t.name)) continue;
    const tj = JSON.parse(fs.readFileSync(path.join(reply, t.jsonFile), 'utf8'));
    const dir = model.configurations[0].directories[t.directoryIndex].build;
    if (inAll(dir, t.name)) artifacts[t.name] = tj.artifacts[0].path;
  }
  need('a', 'default target builds server + workers', BINARIES.every((b) => artifacts[b]),
    BINARIES.map((b) => `${b} -> ${artifacts[b] ?? 'NOT in all'}`).join(', '));
  const copiedFromBuild = copies.filter((c) => c.flags.from).flatMap((c) => c.srcs);
  const missingBins = BINARIES.filter((b) => !copiedFromBuild.includes(path.posix.join(workdir, buildDir, artifacts[b])));
  record('a', 'runtime copies them from there', missingBins.length === 0,
    missingBins.length ? `not copied: ${missingBins.map((b) => path.posix.join(workdir, buildDir, artifacts[b])).join(', ')}` : `${path.posix.join(workdir, buildDir)}/{${BINARIES.map((b) => artifacts[b]).join(',')}}`);

  // --- b. runtime stage: packages and sources -------------------------------------------------
  const runtimeRuns = runtime.instrs.filter((i) => i.kw === 'RUN').flatMap((i) => shellCommands(i.rest));
  const aptPkgs = [];
  const aptFlags = [];
  for (const c of runtimeRuns) {
    if (!['apt-get', 'apt'].includes(c[0]) || !c.includes('install')) continue;
    for (let k = c.indexOf('install') + 1; k < c.length; k++) {
      if (c[k] === '-o' || c[k] === '-t') k++;
      else if (c[k].startsWith('-')) aptFlags.push(c[k]);
      else aptPkgs.push(c[k]);
    }
  }
  need('b', 'runtime apt-get install', aptPkgs.length > 0, aptPkgs.join(' '));
  record('b', 'without recommends', aptFlags.includes('--no-install-recommends'), aptFlags.join(' '));
  const base = basePackages();
  const added = simulateInstall(base, aptPkgs, aptFlags.filter((f) => f === '--no-install-recommends'), tmp);
  const image = new Set([...base, ...added]);
  const toolchain = /^(gcc|g\+\+|cpp|clang|llvm|cmake|make|build-essential|binutils|nodejs|npm|libtool|autoconf|automake|pkg-config|pkgconf|git)(-[\d.]+)?$|-dev$|^clang-|^gcc-\d+$|^g\+\+-\d+$/;
  const bad = [...added].filter((p) => toolchain.test(p));
  record('b', 'no toolchain/-dev package, dependencies included', bad.length === 0,
    bad.length ? bad.join(' ') : `${added.length} packages over a base of ${base.length} (apt-get -s)`);
  const forbiddenSrc = ['server', 'renderer', 'tests', 'bench', 'web/src', 'web/node_modules', 'docker'];
  const srcViolations = [];
  for (const c of copies) {
    for (const s of c.srcs) {
      const rel = c.flags.from ? path.posix.relative(workdir, path.posix.resolve(workdir, s)) : path.posix.normalize(s).replace(/^\.?\/?/, '');
      if (c.flags.from && rel.startsWith('..')) continue;  // outside the sources (e.g. /usr/...)
      const isSrc = rel === '' || rel === '.' || forbiddenSrc.some((f) => rel === f || f.startsWith(rel + '/') || (rel.startsWith(f + '/') && rel !== 'docker/healthcheck.sh'));
      if (isSrc) srcViolations.push(`${s} (line ${c.line})`);
    }
  }
  record('b', 'copies no source folder', srcViolations.length === 0, srcViolations.join(', ') || `${copies.length} COPY lines`);

  // --- c. the binaries' shared libraries against the image's packages -------------------------
  const binPaths = Object.fromEntries(BINARIES.map((b) => [b, path.join(build, artifacts[b])]));
  for (const [name, file] of Object.entries(binPaths)) {
    need('c', `${name} in --build`, fs.existsSync(file), file);
    const ldd = run('ldd', [file]);
    const libs = ldd.stdout.split('\n').map((l) => l.trim()).filter(Boolean);
    const notFound = libs.filter((l) => /not found/.test(l));
    const unmet = [];
    const owners = new Set();
    for (const l of libs) {
      const m = l.match(/=>\s+(\/\S+)/) || l.match(/^(\/\S+)/);
      if (!m) continue;                        // linux-vdso
      const pk = packagesOf(m[1]);
      if (!pk.some((p) => image.has(p))) unmet.push(`${path.basename(m[1])} (${pk.join(',') || 'no package'})`);
      pk.forEach((p) => owners.add(p));
    }
    record('c', `${name}: libraries from image packages`, notFound.length === 0 && unmet.length === 0,
      [...notFound, ...unmet].join(', ') || `${libs.length} libraries, ${owners.size} packages: ${[...owners].filter((p) => !base.includes(p)).join(' ') || 'base only'}`);
  }
  const icd = '/usr/share/vulkan/icd.d/lvp_icd.x86_64.json';
  const icdPkg = fs.existsSync(icd) ? packagesOf(icd) : [];
  record('c', 'a Vulkan driver for hosts without GPU', icdPkg.some((p) => image.has(p)), `lavapipe (${icd}) from ${icdPkg.join(',') || 'no package here'}`);

  // --- e. image metadata ----------------------------------------------------------------------
  const last = (kw) => runtime.instrs.filter((i) => i.kw === kw).at(-1);
  const user = last('USER')?.rest ?? '';
  const userName = user.split(':')[0];
  record('e', 'USER non-root', !!user && !['0', 'root'].includes(userName) && !(user.split(':')[1] ?? '').match(/^(0|root)$/), user || 'none (root)');
  const volumes = runtime.instrs.filter((i) => i.kw === 'VOLUME').flatMap((i) => (i.rest.startsWith('[') ? JSON.parse(i.rest) : i.rest.split(/\s+/)));
  record('e', 'VOLUME /data', volumes.includes('/data'), volumes.join(' ') || 'none');
  const hc = last('HEALTHCHECK');
  const hcCmd = hc && hc.rest.match(/CMD\s+([\s\S]*)$/);
  need('e', 'HEALTHCHECK', !!hcCmd, hc ? hc.rest.replace(/\s+/g, ' ') : 'none');
  const stopsig = last('STOPSIGNAL')?.rest ?? 'SIGTERM (default)';
  record('e', 'STOPSIGNAL SIGTERM', /^(SIGTERM|15)\b/.test(stopsig), stopsig);
  const env = {};
  for (const i of runtime.instrs.filter((x) => x.kw === 'ENV')) Object.assign(env, parseEnv(i.rest));
  record('e', 'ENV NVIDIA_DRIVER_CAPABILITIES', /graphics/.test(env.NVIDIA_DRIVER_CAPABILITIES ?? '') && /compute/.test(env.NVIDIA_DRIVER_CAPABILITIES ?? ''),
    env.NVIDIA_DRIVER_CAPABILITIES ?? 'unset');
  const entry = last('ENTRYPOINT') ? execForm(last('ENTRYPOINT')) : { exec: true, argv: [] };
  const cmd = last('CMD') ? execForm(last('CMD')) : { exec: true, argv: [] };
  record('e', 'ENTRYPOINT exec form (the server is PID 1 and gets SIGTERM)', entry.exec && cmd.exec && entry.argv.length > 0,
    JSON.stringify([...entry.argv, ...cmd.argv]));
  const serverArgv = [...entry.argv, ...cmd.argv];
  const argOf = (flag) => {
    for (let k = 1; k < serverArgv.length; k++) {
      if (serverArgv[k] === flag) return serverArgv[k + 1];
      if (serverArgv[k].startsWith(flag + '=')) return serverArgv[k].slice(flag.length + 1);
    }
    return undefined;
  };
  const imagePort = argOf('--port') ?? '8080';
  const exposed = runtime.instrs.filter((i) => i.kw === 'EXPOSE').flatMap((i) => i.rest.split(/\s+/)).map((p) => p.replace(/\/tcp$/, ''));
  record('e', 'EXPOSE the server port', exposed.includes(imagePort), `EXPOSE ${exposed.join(' ')}; --port ${imagePort}`);
  const dataDir = argOf('--data-dir');
  record('e', 'data folder is the volume', !!dataDir && volumes.includes(dataDir), `--data-dir ${dataDir ?? '(default ./data)'}`);
  record('e', 'listens beyond loopback', argOf('--host') === '0.0.0.0', `--host ${argOf('--host') ?? '(default 127.0.0.1)'}`);

  // --- d. the runtime file system, served ------------------------------------------------------
  const fsroot = path.join(tmp, 'image');
  fs.mkdirSync(fsroot, { mode: 0o755 });
  const inImage = (p) => path.join(fsroot, p);
  const fromBuildStage = (p) => {
    const abs = path.posix.resolve(workdir, p);
    const bdir = path.posix.join(workdir, buildDir);
    if (abs === bdir || abs.startsWith(bdir + '/')) return path.join(build, path.posix.relative(bdir, abs));
    if (abs === workdir || abs.startsWith(workdir + '/')) return path.join(root, path.posix.relative(workdir, abs));
    throw new Error(`COPY --from source ${p} is outside the build stage's ${workdir}`);
  };
  let rtWorkdir = '/';
  let copied = 0;
  const users = {};                           // name -> uid, from RUN useradd
  for (const i of runtime.instrs) {
    if (i.kw === 'WORKDIR') {
      rtWorkdir = path.posix.resolve(rtWorkdir, i.rest);
      fs.mkdirSync(inImage(rtWorkdir), { recursive: true });
    } else if (i.kw === 'RUN') {
      for (const c of shellCommands(i.rest)) {
        if (c[0] === 'useradd') {
          const k = c.indexOf('--uid') >= 0 ? c.indexOf('--uid') : c.indexOf('-u');
          users[c.at(-1)] = k >= 0 ? Number(c[k + 1]) : 1000;
          if (c.includes('--create-home') || c.includes('-m')) fs.mkdirSync(inImage(`/home/${c.at(-1)}`), { recursive: true });
        } else if (c[0] === 'mkdir') {
          for (const p of c.slice(1).filter((w) => !w.startsWith('-'))) fs.mkdirSync(inImage(path.posix.resolve(rtWorkdir, p)), { recursive: true });
        } else if (c[0] === 'chown') {
          const words = c.slice(1).filter((w) => !w.startsWith('-'));
          const [u, g] = words[0].split(':');
          const uid = /^\d+$/.test(u) ? Number(u) : users[u];
          const gid = g === undefined ? uid : /^\d+$/.test(g) ? Number(g) : users[g];
          for (const p of words.slice(1)) if (process.getuid() === 0) fs.chownSync(inImage(path.posix.resolve(rtWorkdir, p)), uid, gid);
        }
      }
    } else if (i.kw === 'COPY' || i.kw === 'ADD') {
      const c = parseCopy(i.rest);
      const dest = path.posix.resolve(rtWorkdir, c.dest);
      const intoDir = c.dest.endsWith('/') || c.srcs.length > 1;
      for (const s of c.srcs) {
        if (/[*?[]/.test(s)) throw new Error(`line ${i.line}: globs are not emulated (${s})`);
        const from = c.flags.from ? fromBuildStage(s) : path.join(root, s);
        if (!fs.existsSync(from)) need('d', `COPY ${s}`, false, `${from} missing (make build builds it)`);
        const to = fs.statSync(from).isDirectory() ? inImage(dest) : intoDir ? inImage(path.posix.join(dest, path.posix.basename(s))) : inImage(dest);
        fs.mkdirSync(path.dirname(to), { recursive: true });
        fs.cpSync(from, to, { recursive: true, dereference: true });
        copied++;
      }
    }
  }
  for (const v of volumes) fs.mkdirSync(inImage(v), { recursive: true });
  const files = walkFiles(fsroot);
  const bytes = files.reduce((n, f) => n + fs.statSync(f).size, 0);
  const sources = files.filter((f) => /\.(c|cc|cpp|cxx|h|hh|hpp|hxx|ipp)$|\/CMakeLists\.txt$/.test(f) || /\/node_modules\/|\/web\/src\//.test(f));
  record('d', 'COPY into a folder: no C++ sources, node_modules, web/src', sources.length === 0,
    sources.length ? sources.slice(0, 5).map((f) => path.relative(fsroot, f)).join(', ') : `${copied} sources copied: ${files.length} files, ${(bytes / 1048576).toFixed(1)} MiB`);

  // Where the server will look: --root, else $BRDFA_ROOT, else the source tree it was built from
  // (which does not exist in the image).
  const imageRoot = argOf('--root') ?? env.BRDFA_ROOT;
  need('d', 'the server is told its root', !!imageRoot && fs.existsSync(inImage(imageRoot)), `--root/BRDFA_ROOT = ${imageRoot ?? 'unset'}`);
  for (const w of WORKERS) {
    need('d', `${w} beside the server`, fs.existsSync(path.join(path.dirname(inImage(entry.argv[0])), w)), path.posix.join(path.posix.dirname(entry.argv[0]), w));
  }
  // Markers that only the image's copies carry, so a server that read the build tree instead
  // (its compiled-in default root) cannot pass.
  const marker = `deploy-test-${crypto.randomBytes(6).toString('hex')}`;
  fs.appendFileSync(inImage(path.posix.join(imageRoot, 'web/index.html')), `<!-- ${marker} -->\n`);
  const probeBrdf = `zz_deploy_probe_${marker.slice(-6)}`;
  fs.copyFileSync(inImage(path.posix.join(imageRoot, 'shaders/brdfs/lambert.brdf')), inImage(path.posix.join(imageRoot, `shaders/brdfs/${probeBrdf}.brdf`)));

  // The command line, moved into the folder.
  const port = await freePort();
  const remap = (a) => (a.startsWith('/') && fs.existsSync(inImage(a)) ? inImage(a) : a);
  const argvRun = serverArgv.map((a, k) => {
    const prev = serverArgv[k - 1];
    if (prev === '--port') return String(port);
    if (prev === '--host') return '127.0.0.1';
    if (a.startsWith('--port=')) return `--port=${port}`;
    if (a.startsWith('--host=')) return '--host=127.0.0.1';
    if (a.startsWith('--') && a.includes('=')) return a.slice(0, a.indexOf('=') + 1) + remap(a.slice(a.indexOf('=') + 1));
    return remap(a);
  });
  const runEnv = { ...cleanEnv };
  for (const [k, v] of Object.entries(env)) runEnv[k] = remap(v);
  // As `docker run -e BRDFA_REPLICA=...` or the StatefulSet's env: the tag without a flag.
  const replicaTag = `deploytest${marker.slice(-4)}`;
  runEnv.BRDFA_REPLICA = replicaTag;
  const uid = /^\d+$/.test(userName) ? Number(userName) : users[userName];
  const gidPart = user.split(':')[1];
  const gid = gidPart === undefined ? uid : /^\d+$/.test(gidPart) ? Number(gidPart) : users[gidPart];
  const asUser = process.getuid() === 0 && Number.isInteger(uid);
  const homeName = Object.keys(users).find((n) => users[n] === uid);
  runEnv.HOME = homeName && fs.existsSync(inImage(`/home/${homeName}`)) ? inImage(`/home/${homeName}`) : fsroot;
  if (asUser && homeName) fs.chownSync(runEnv.HOME, uid, gid);
  const spawnOpts = { cwd: inImage(rtWorkdir), env: runEnv, stdio: ['ignore', 'pipe', 'pipe'], ...(asUser ? { uid, gid } : {}) };
  const child = spawn(argvRun[0], argvRun.slice(1), spawnOpts);
  setServer(child);
  let out = '';
  let err = '';
  child.stdout.on('data', (d) => { out += d; });
  child.stderr.on('data', (d) => { err += d; });
  const exited = new Promise((r) => child.on('exit', (code, sig) => r({ code, sig })));
  child.exitInfo = exited;
  const started = Date.now();
  const up = await Promise.race([
    (async () => { while (!/listening on/.test(out)) await sleep(50); return true; })(),
    exited.then(() => false),
    sleep(120000).then(() => false),
  ]);
  need('d', `server starts ${asUser ? `as uid ${uid}` : `as uid ${process.getuid()} (not root: USER not applied)`}`, up,
    up ? `${argvRun.map((a) => a.replace(fsroot, '<img>')).join(' ')} (${Date.now() - started} ms)` : `no "listening on": ${err.trim().slice(-400)}`);

  const page = await httpGet(port, '/');
  const html = page.body.toString('utf8');
  record('d', 'GET / is the index page from the image', page.status === 200 && /text\/html/.test(page.headers['content-type']) &&
    /<script[^>]+src="dist\/main\.js"/.test(html) && html.includes(marker), `${page.status} ${page.headers['content-type']}, ${html.length} bytes, marker ${html.includes(marker) ? 'found' : 'MISSING'}`);
  const main = await httpGet(port, '/dist/main.js');
  record('d', 'GET /dist/main.js', main.status === 200 && /javascript/.test(main.headers['content-type']) && main.body.length > 10000,
    `${main.status} ${main.headers['content-type']}, ${main.body.length} bytes`);
  // Every local file the page and the bundle's entry name: style sheets, chunks.
  const refs = new Set();
  for (const m of html.matchAll(/(?:src|href)="([^"#:]+)"/g)) if (!m[1].endsWith('/')) refs.add('/' + m[1].replace(/^\.?\//, ''));
  for (const m of main.body.toString('utf8').matchAll(/["'`]\.\/(chunk-[\w-]+\.js|[\w-]+\.css)["'`]/g)) refs.add('/dist/' + m[1]);
  const missingRefs = [];
  for (const r of refs) if ((await httpGet(port, r)).status !== 200) missingRefs.push(r);
  record('d', 'every file the page and main.js name', refs.size > 1 && missingRefs.length === 0, missingRefs.length ? `missing: ${missingRefs.join(' ')}` : [...refs].join(' '));
  const health = await httpGet(port, '/api/health');
  let hj = {};
  try { hj = JSON.parse(health.body.toString('utf8')); } catch { /* reported below */ }
  record('d', 'GET /api/health', health.status === 200 && hj.status === 'ok', `${health.status} ${hj.status ?? ''} device ${hj.device?.name ?? '?'} (${hj.device?.type ?? '?'})`);
  // Features of servers with --replica; an older binary is reported, not failed.
  const tag = health.headers['x-brdfa-replica'];
  rows.push(['d', 'BRDFA_REPLICA from the environment', tag === undefined ? 'info' : tag === replicaTag ? 'ok' : 'FAIL',
    tag === undefined ? 'no X-Brdfa-Replica header: this server predates --replica' : `X-Brdfa-Replica: ${tag}`]);
  if (tag !== undefined && tag !== replicaTag) failed++;
  const ready = await httpGet(port, '/api/ready');
  rows.push(['d', 'GET /api/ready (readiness probe)', ready.status === 200 ? 'ok' : ready.status === 404 ? 'info' : 'FAIL',
    ready.status === 404 ? '404: this server predates /api/ready' : `${ready.status}`]);
  if (![200, 404].includes(ready.status)) failed++;
  const brdfs = await httpGet(port, '/api/brdfs');
  record('d', 'built-in BRDFs from the image\'s shaders/', brdfs.status === 200 && brdfs.body.toString('utf8').includes(probeBrdf),
    `${brdfs.status}, probe ${probeBrdf} ${brdfs.body.toString('utf8').includes(probeBrdf) ? 'listed' : 'NOT listed'}`);
  const lambert = fs.readFileSync(inImage(path.posix.join(imageRoot, 'shaders/brdfs/lambert.brdf')), 'utf8');
  const v = await httpPost(port, '/api/brdfs/validate', lambert);
  record('d', 'POST /api/brdfs/validate (a compile)', v.status === 200, `${v.status}`);
  const kids = descendants(child.pid);
  const binDir = path.dirname(inImage(entry.argv[0]));
  const outside = kids.filter((k) => path.dirname(k.exe) !== binDir);
  const seen = WORKERS.filter((w) => kids.some((k) => path.basename(k.exe) === w));
  record('d', 'workers run from the image', seen.length === WORKERS.length && outside.length === 0,
    `${kids.length} processes: ${seen.join(', ') || 'no worker'}${outside.length ? `; outside: ${outside.map((k) => k.exe).join(' ')}` : ''}`);
  const dataFiles = walkFiles(inImage(dataDir));
  record('d', 'the data volume is written', dataFiles.length > 0, `${dataFiles.length} files under ${dataDir}`);

  // The HEALTHCHECK, run as the image would, against the server and against a closed port.
  const hcForm = execForm({ rest: hcCmd[1].trim() });
  const hcRun = async (p) => {
    const a = hcForm.argv.map((x) => (hcForm.exec ? (x === imagePort ? String(p) : remap(x)) : x));
    if (!hcForm.exec) a[2] = a[2].replaceAll(imagePort, String(p)).replace(/(\/[\w./-]+)/g, (m) => remap(m));
    const r = spawnSync(a[0], a.slice(1), { env: runEnv, encoding: 'utf8', timeout: 30000, ...(asUser ? { uid, gid } : {}) });
    return { status: r.status, argv: a };
  };
  const hcOk = await hcRun(port);
  const closed = await freePort();
  const hcBad = await hcRun(closed);
  record('d', 'HEALTHCHECK passes, and fails on a closed port', hcOk.status === 0 && hcBad.status !== 0 && hcBad.status !== null,
    `exit ${hcOk.status} / ${hcBad.status}: ${hcOk.argv.map((a) => a.replace(fsroot, '<img>')).join(' ')}`);
}

async function stopServer(child) {
  const kids = descendants(child.pid);
  const t0 = Date.now();
  child.kill('SIGTERM');
  const res = await Promise.race([child.exitInfo, sleep(30000).then(() => null)]);
  if (!res) child.kill('SIGKILL');
  await sleep(200);
  const left = kids.filter((k) => fs.existsSync(`/proc/${k.pid}`) && (() => { try { return fs.readlinkSync(`/proc/${k.pid}/exe`) === k.exe; } catch { return false; } })());
  for (const k of left) { try { process.kill(k.pid, 'SIGKILL'); } catch { /* gone */ } }
  rows.push(['d', 'server stopped (SIGTERM)', 'info', res ? `exit ${res.code ?? res.sig} after ${Date.now() - t0} ms${left.length ? `, ${left.length} workers killed` : ''}` : 'still running after 30 s: killed']);
}

main();
