// Browser test of identities in the UI (docs/api.md, Identities and ownership), in Debian's
// Chromium driven by playwright-core, against the real server binary in `--auth tokens` mode.
// Registered in CTest as `web_auth` (tests/CMakeLists.txt):
//   node tests/web/auth.mjs --server build/server/brdfa-server --root . --artifacts build/web-artifacts
// Two students join through the teacher's join link with display names that are HTML and
// script; every string they choose (display names, upload file names, preset names, compile
// diagnostics quoting their text) must show as text and never run. Their editor compiles into
// `<namespace>scratch-<session>` and Save as stores under their namespace. The teacher (the admin
// token) sees both sessions in the Class tab with live thumbnails and watches one full size.
// Pages on other origins post forms at the API (cross-site request forgery): nothing changes.
// Exit 0 pass, 1 fail, 77 skipped (no browser or no web/node_modules).
import assert from 'node:assert/strict';
import { existsSync, mkdirSync, mkdtempSync, rmSync, writeFileSync } from 'node:fs';
import { createServer } from 'node:http';
import { createRequire } from 'node:module';
import { tmpdir } from 'node:os';
import { join, resolve } from 'node:path';
import { execFileSync } from 'node:child_process';
import { randomBytes } from 'node:crypto';
import { reportAndExit, startServer } from './server.mjs';
import { waitForFrame } from './frames.mjs';

const CHROMIUM = process.env.BRDFA_CHROMIUM || '/usr/bin/chromium';
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

// What each student chooses. Display names are free text (at most 64 characters); BRDF and
// preset names are [A-Za-z0-9_-], so markup reaches the page through display names, upload file
// names, a refused preset name and compile diagnostics that quote the file's text.
const STUDENTS = [
  {
    key: 'alice',
    displayName: '<img src=x onerror="window.__xss=1">Alice',
    upload: '<img src=x onerror=window.__xss=1>.obj',
    preset: '<img src=x onerror=window.__xss=1>',
    // A parameter name the parser refuses, quoted in its diagnostic.
    badSource: 'analytic\n::begin parameters\nfloat <img/src/onerror=window.__xss=1> 0 1 0.5\n::end parameters\n' +
      '::begin shader\nvec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return vec3(0.5); }\n::end shader\n',
    quoted: '<img/src/onerror=window.__xss=1>',
  },
  {
    key: 'bob',
    displayName: '<script>window.__xss=1</script><svg onload=window.__xss=1>Bob',
    upload: '<svg onload=window.__xss=1>.obj',
    preset: '<script>window.__xss=1</script>',
    // A parameter type the parser refuses, quoted in its diagnostic.
    badSource: 'analytic\n::begin parameters\n<script>window.__xss=1</script> k 0 1 0.5\n::end parameters\n' +
      '::begin shader\nvec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return vec3(0.5); }\n::end shader\n',
    quoted: '<script>window.__xss=1</script>',
  },
];

// A valid BRDF whose comments carry markup (the editor shows its text as text).
const SOURCE = `analytic
# <img src=x onerror="window.__xss=1"> a comment with markup
::begin parameters
float roughness 0.05 1 0.4
color tint 0.9 0.6 0.3
::end parameters
::begin shader
const float PI = 3.14159265358979323846;
// <script>window.__xss=1</script>
vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)
{
    if (dot(N, L) <= 0.0 || dot(N, V) <= 0.0) return vec3(0.0);
    vec3 H = normalize(L + V);
    float a2 = roughness * roughness * roughness * roughness;
    float d = dot(N, H) * dot(N, H) * (a2 - 1.0) + 1.0;
    return tint / PI + vec3(0.2 * a2 / (PI * d * d));
}
::end shader
`;

// A tetrahedron (the server makes normals and UVs).
const TETRA = 'v 0 1 0\nv -1 -0.6 0.8\nv 1 -0.6 0.8\nv 0 -0.6 -1\nf 1 2 3\nf 1 3 4\nf 1 4 2\nf 2 4 3\n';

function args() {
  const out = { server: process.env.BRDFA_SERVER_BINARY, root: process.env.BRDFA_ROOT, artifacts: 'web-artifacts' };
  const a = process.argv.slice(2);
  for (let i = 0; i < a.length; i += 2) out[a[i].replace(/^--/, '')] = a[i + 1];
  if (!out.server || !out.root) {
    console.error('usage: auth.mjs --server BINARY --root SOURCE_DIR [--artifacts DIR]');
    process.exit(2);
  }
  return { ...out, root: resolve(out.root), artifacts: resolve(out.artifacts) };
}

async function until(what, fn, timeout = 20000) {
  const end = Date.now() + timeout;
  let last;
  for (;;) {
    try { last = await fn(); } catch (e) { last = e; }
    if (last && !(last instanceof Error)) return last;
    if (Date.now() > end) throw new Error(`timed out waiting for ${what}${last instanceof Error ? ` (last: ${last.message})` : ''}`);
    await sleep(100);
  }
}

/** A request from node (no Origin, no Sec-Fetch-Site: a script, as curl). Resolves {status, body, headers}. */
async function call(env, method, path, { token, json, text, headers = {} } = {}) {
  const h = { ...headers };
  if (token) h.Authorization = `Bearer ${token}`;
  let body;
  if (json !== undefined) { h['Content-Type'] = 'application/json'; body = JSON.stringify(json); }
  if (text !== undefined) { h['Content-Type'] = 'text/plain'; body = text; }
  const res = await fetch(env.server.url + path, { method, headers: h, body });
  const raw = await res.text();
  let parsed = raw;
  try { parsed = raw ? JSON.parse(raw) : null; } catch { /* not JSON */ }
  return { status: res.status, body: parsed, headers: res.headers };
}

/** As call(), and fails unless the answer is 2xx: resolves the body. */
async function ok(env, method, path, opts) {
  const r = await call(env, method, path, opts);
  if (r.status < 200 || r.status > 299) throw new Error(`${method} ${path}: ${r.status} ${JSON.stringify(r.body)}`);
  return r.body;
}
const admin = (env, method, path, opts = {}) => ok(env, method, path, { ...opts, token: env.adminToken });

// Page script (an init script, before the page's own): records every element that arrives in
// the document with an event-handler attribute, and every inline <script>. The UI has none.
function watchForInjection() {
  window.__injected = [];
  const check = (e) => {
    if ((e.tagName === 'SCRIPT' && !e.src) || [...e.attributes].some((a) => a.name.toLowerCase().startsWith('on'))) {
      window.__injected.push(e.outerHTML.slice(0, 200));
    }
  };
  new MutationObserver((records) => {
    for (const r of records) {
      for (const n of r.addedNodes) {
        if (n.nodeType !== 1) continue;
        check(n);
        for (const e of n.querySelectorAll('*')) check(e);
      }
    }
  }).observe(document, { childList: true, subtree: true });
}

/** A browser context whose pages are watched for injected markup; its pages record their requests. */
async function newContext(env, label, { token } = {}) {
  const context = await env.browser.newContext({ viewport: { width: 1280, height: 720 } });
  await context.addInitScript(watchForInjection);
  if (token) {
    // The teacher's browser holds the admin token, on the server's origin only.
    await context.addInitScript(({ origin, token }) => {
      if (location.origin === origin) localStorage.setItem('brdfa.token', token);
    }, { origin: new URL(env.server.url).origin, token });
  }
  env.contexts.push(context);
  const page = await context.newPage();
  page.label = label;
  page.errors = [];
  page.requests = [];
  page.on('pageerror', (e) => page.errors.push(`${label} page error: ${e.message}`));
  page.on('request', (r) => { if (r.url().startsWith(`${env.server.url}/api/`)) page.requests.push(r); });
  env.pages.push(page);
  return { context, page };
}

/** The whole CodeMirror text; `source` replaces it (no compile: the caller clicks Compile). */
const editorText = (page, source) => page.evaluate((source) => {
  const content = document.querySelector('.cm-content');
  const view = content.cmTile?.root?.view ?? content.cmView?.view;   // EditorView.findFromDOM, from outside the bundle
  if (source !== undefined) view.dispatch({ changes: { from: 0, to: view.state.doc.length, insert: source } });
  return view.state.doc.toString();
}, source);

/** The page shows `text` as text (in what a person reads, not in an attribute). */
async function showsText(page, text, where = 'body') {
  await until(`${page.label}: ${JSON.stringify(text)} shown as text in ${where}`, async () =>
    (await page.locator(where).first().innerText()).includes(text));
}

/** No script of a payload ran, and no payload became an element, in any page so far. */
async function assertNoInjection(env) {
  for (const page of env.pages) {
    if (page.isClosed()) continue;
    for (const frame of page.frames()) {
      const got = await frame.evaluate(() => ({
        xss: window.__xss,
        injected: window.__injected || [],
        elements: [...document.querySelectorAll('img[src="x"], img[onerror], svg[onload], script:not([src])')].map((e) => e.outerHTML.slice(0, 120)),
      })).catch(() => null);   // a frame navigating away
      if (!got) continue;
      assert.equal(got.xss, undefined, `${page.label}: a payload's script ran (window.__xss = ${got.xss})`);
      assert.deepEqual(got.injected, [], `${page.label}: markup with handlers or inline scripts arrived in the document`);
      assert.deepEqual(got.elements, [], `${page.label}: payload elements in the document`);
    }
  }
}

const sessionIds = async (env) => (await admin(env, 'GET', '/api/sessions')).map((s) => s.id).sort();
const joinCodeIds = async (env) => (await admin(env, 'GET', '/api/auth/join-codes')).map((c) => c.id).sort();
const userNames = async (env) => (await admin(env, 'GET', '/api/auth/users')).map((u) => u.user).sort();

/**
 * Serves `html` (with SERVER replaced by the API's base URL) from a second loopback server: a
 * page of another origin. Resolves {port, close}.
 */
function attackerSite(html) {
  return new Promise((resolveSite) => {
    const site = createServer((req, res) => {
      res.writeHead(200, { 'Content-Type': 'text/html; charset=utf-8' });
      res.end(html);
    });
    site.listen(0, '127.0.0.1', () => resolveSite({ port: site.address().port, close: () => new Promise((r) => site.close(r)) }));
  });
}

/**
 * A page of auto-submitting forms at the API `server`: each form {path, body, smuggle?} posts
 * `body` as text/plain (a JSON body without a preflight). A form with `smuggle` posts instead a
 * whole HTTP request as its body (name = the request, value empty: text/plain sends
 * `name=value` CRLF): a server that answers the form without reading its body would read that
 * body as the next request on the connection, one with no Origin to refuse.
 */
function forgeryPage(server, forms) {
  const host = new URL(server).host;
  const spec = forms.map((f) => ({
    action: `${server}${f.path}`,
    name: f.smuggle
      ? `${f.smuggle.method} ${f.smuggle.path} HTTP/1.1\r\nHost: ${host}\r\nContent-Type: application/json\r\n` +
        `Content-Length: ${Buffer.byteLength(f.smuggle.body)}\r\n\r\n${f.smuggle.body}`
      : f.body.slice(0, -2),
    value: f.smuggle ? '' : f.body.slice(-2),   // the JSON split before its closing `"}`, where the = goes
  }));
  return `<!doctype html><meta charset="utf-8"><title>another site</title><body>
<script>
const forms = ${JSON.stringify(spec)};
forms.forEach((f, i) => {
  const frame = document.createElement('iframe');
  frame.name = 't' + i;
  document.body.append(frame);
  const form = document.createElement('form');
  Object.assign(form, { method: 'POST', enctype: 'text/plain', action: f.action, target: frame.name });
  const input = document.createElement('input');
  input.type = 'hidden';
  input.name = f.name;
  input.value = f.value;
  form.append(input);
  document.body.append(form);
  form.submit();
});
</script>`;
}

/** Opens the forgery page at `origin` in `context`; resolves the answers its forms got from the API. */
async function submitForgeries(env, server, context, origin, count, label) {
  const page = await context.newPage();
  page.label = label;
  const answers = [];
  page.on('response', (r) => { if (r.url().startsWith(`${server}/api/`)) answers.push(r); });
  await page.goto(`${origin}/`);
  await until(`${label}: ${count} forms answered`, async () => answers.length >= count, 15000).catch(() => {});
  await sleep(1000);   // what a smuggled request would do, done
  const out = [];
  for (const r of answers) {
    const body = await r.text().catch(() => '');
    out.push({ path: new URL(r.url()).pathname, status: r.status(), body });
  }
  await page.close();
  return out;
}

/** What went wrong with the answers of `count` forged forms: each should be 403 cross_site. */
function forgeryProblems(answers, count, origin) {
  const problems = [];
  if (answers.length < count) problems.push(`from ${origin}: ${answers.length} of ${count} forms answered`);
  for (const a of answers) {
    if (a.status !== 403 || !/cross_site/.test(a.body)) problems.push(`POST ${a.path} from ${origin}: ${a.status} ${a.body}`);
  }
  return problems;
}

const checks = [
  ['tokens mode: no token is 401; the admin token is the teacher; a join code is made', async (env) => {
    env.fatal = true;
    const anon = await call(env, 'GET', '/api/auth/me');
    assert.equal(anon.status, 401, `GET /api/auth/me without a token: ${anon.status} ${JSON.stringify(anon.body)}`);
    assert.match(anon.headers.get('www-authenticate') || '', /^Bearer/, 'WWW-Authenticate: Bearer');
    const me = await admin(env, 'GET', '/api/auth/me');
    assert.equal(me.mode, 'tokens');
    assert.equal(me.role, 'teacher');
    assert.equal(me.namespace, '');
    const jc = await admin(env, 'POST', '/api/auth/join-codes', { json: { ttl_minutes: 60 } });
    assert.match(jc.code, /^[a-z0-9]{16}$/, `join code ${jc.code}`);
    assert.equal(jc.join_path, `/?join=${jc.code}`);
    env.code = jc.code;
    env.fatal = false;
  }],

  ['a page without a token asks for one; an unknown join code is refused with a message', async (env) => {
    const { page } = await newContext(env, 'anonymous');
    await page.goto(`${env.server.url}/`);
    await page.locator('#auth .auth-token').waitFor({ state: 'visible' });
    assert.equal(await page.locator('main').isVisible(), false, 'the app is not shown without an identity');
    assert.match(await page.locator('#auth').innerText(), /token or a join link/);
    await page.screenshot({ path: join(env.artifacts, 'auth-01-token-needed.png') });
    // A pasted token that is not accepted stays on the screen, saying so.
    await page.fill('#auth .auth-token-input', 'brdfa_not-a-real-token-not-a-real-token-00000');
    await page.click('#auth .auth-token button');
    await showsText(page, 'not accepted', '#auth .auth-message');

    await page.goto(`${env.server.url}/?join=zzzzzzzzzzzzzzzz`);
    await page.locator('#auth .auth-join').waitFor({ state: 'visible' });
    await page.fill('#auth .auth-name', 'Mallory');
    await page.click('#auth .auth-join button');
    await showsText(page, 'unknown or has expired', '#auth .auth-message');
    await page.close();
  }],

  ['two students join through the link; their HTML display names show as text', async (env) => {
    env.fatal = true;
    for (const s of STUDENTS) {
      const { page } = await newContext(env, s.key);
      s.page = page;
      await page.goto(`${env.server.url}/?join=${env.code}`);
      await page.locator('#auth .auth-join').waitFor({ state: 'visible' });
      await page.screenshot({ path: join(env.artifacts, `auth-02-join-${s.key}.png`) });
      await page.fill('#auth .auth-name', s.displayName);
      await page.click('#auth .auth-join button');
      await waitForFrame(page, { minVariance: 20, timeout: 60000 });
      const url = new URL(page.url());
      assert.equal(url.searchParams.get('join'), null, 'the join code is gone from the address');
      s.sid = url.searchParams.get('session');
      assert.ok(s.sid, `the page has a session (${page.url()})`);
      s.token = await page.evaluate(() => localStorage.getItem('brdfa.token'));
      assert.match(s.token || '', /^brdfa_[A-Za-z0-9_-]{43}$/, 'the token is kept in localStorage brdfa.token');
      const me = await ok(env, 'GET', '/api/auth/me', { token: s.token });
      assert.equal(me.role, 'student');
      assert.equal(me.display_name, s.displayName, 'the server keeps the display name as typed');
      assert.equal(me.namespace, `${me.user}/`);
      s.user = me.user;
      s.ns = me.namespace;
      assert.equal(await page.locator('#whoami .whoami-name').innerText(), s.displayName, 'who am I: the display name, as text');
      assert.equal(await page.locator('#whoami .whoami-role').innerText(), 'student');
      assert.match(await page.locator('#whoami').innerText(), /tokens mode/);
      assert.equal(await page.locator('.tabs [data-tab="tab-class"]').count(), 0, 'a student has no Class tab');
    }
    await assertNoInjection(env);
    env.fatal = false;
  }],

  ['the editor compiles into <namespace>scratch-<session>; Save as stores under the namespace', async (env) => {
    for (const s of STUDENTS) {
      const { page } = s;
      await page.bringToFront();
      await page.locator('.cm-content').waitFor();
      await until(`${s.key}: the editor holds the first object's BRDF`, async () => (await editorText(page)).startsWith('analytic'));
      await editorText(page, SOURCE);
      await page.click('#editor .compile');
      const scratch = `${s.ns}scratch-${s.sid}`;
      await until(`${s.key}: the object to render ${scratch}`, async () =>
        (await admin(env, 'GET', `/api/sessions/${s.sid}/scene`)).objects[0].brdf === scratch);
      const puts = page.requests.filter((r) => r.method() === 'PUT' && r.url().includes('/api/brdfs/'));
      assert.ok(puts.some((r) => new URL(r.url()).pathname === `/api/brdfs/${s.ns}scratch-${s.sid}`),
        `the scratch PUT carries the slash: ${puts.map((r) => r.url()).join(', ')}`);

      page.once('dialog', (d) => d.accept('xss_brdf'));
      await page.click('#library .lib-saveas');
      const saved = `${s.ns}xss_brdf`;
      await until(`${s.key}: the object to render ${saved}`, async () =>
        (await admin(env, 'GET', `/api/sessions/${s.sid}/scene`)).objects[0].brdf === saved);
      assert.ok(page.requests.some((r) => r.method() === 'PUT' && new URL(r.url()).pathname === `/api/brdfs/${s.ns}xss_brdf`),
        'Save as PUTs /api/brdfs/<user>/xss_brdf');
      const mine = await ok(env, 'GET', `/api/brdfs/${saved}`, { token: s.token });
      assert.equal(mine.owner, s.user, 'the saved BRDF is the student\'s');
      await until(`${s.key}: the library list to show ${saved}`, async () => (await page.locator('#library .library-list').inputValue()) === saved);
      assert.equal(await page.locator('#library .lib-save').isDisabled(), false, 'their own BRDF can be saved again');
      assert.equal(await editorText(page), SOURCE, 'the editor shows the markup in comments as text');
      await showsText(page, '<script>window.__xss=1</script>', '#editor .cm-content');
    }
    await assertNoInjection(env);
  }],

  ['an HTML preset name is refused as text; a valid preset saves under the namespaced BRDF', async (env) => {
    for (const s of STUDENTS) {
      const { page } = s;
      await page.bringToFront();
      await page.locator('#params .presets').waitFor({ state: 'visible' });
      page.once('dialog', (d) => d.accept(s.preset));
      await page.click('#params .preset-save');
      await showsText(page, `"${s.preset}" is not a valid preset name`, '#editor .status');
      page.once('dialog', (d) => d.accept('p1'));
      await page.click('#params .preset-save');
      await until(`${s.key}: preset p1 stored`, async () =>
        (await ok(env, 'GET', `/api/brdfs/${s.ns}xss_brdf/presets`, { token: s.token })).includes('p1'));
      await until(`${s.key}: p1 in the preset list`, async () =>
        (await page.locator('#params .preset-list option').allTextContents()).includes('p1'));
    }
    await assertNoInjection(env);
  }],

  ['an uploaded file named with HTML shows its name as text', async (env) => {
    for (const s of STUDENTS) {
      const { page } = s;
      await page.bringToFront();
      await page.click('.tabs [data-tab="tab-objects"]');
      await page.setInputFiles('#objects .obj-mesh-upload', { name: s.upload, mimeType: 'text/plain', buffer: Buffer.from(TETRA) });
      const asset = await until(`${s.key}: the upload listed`, async () =>
        (await ok(env, 'GET', '/api/assets?kind=mesh', { token: s.token })).find((a) => a.name === s.upload));
      await showsText(page, `uploaded ${s.upload} as ${asset.id}`, '#objects .obj-status');
      await until(`${s.key}: the mesh list to name the upload`, async () =>
        (await page.locator('#objects .obj-mesh option').allTextContents()).includes(`${s.upload} (${asset.id})`));
      await page.screenshot({ path: join(env.artifacts, `auth-03-upload-${s.key}.png`) });
      await page.click('.tabs [data-tab="tab-editor"]');
    }
    await assertNoInjection(env);
  }],

  ['compile diagnostics that quote HTML show as text', async (env) => {
    for (const s of STUDENTS) {
      const { page } = s;
      await page.bringToFront();
      await editorText(page, s.badSource);
      await page.click('#editor .compile');
      await showsText(page, s.quoted, '#editor .diagnostics');
      await page.screenshot({ path: join(env.artifacts, `auth-04-diagnostic-${s.key}.png`) });
      // Back to the saved text (Revert asks first).
      page.once('dialog', (d) => d.accept());
      await page.click('#library .lib-revert');
      await until(`${s.key}: the saved text back`, async () => (await editorText(page)) === SOURCE);
    }
    await assertNoInjection(env);
  }],

  ['every request carries the token and X-Brdfa-Client: web; images carry the view key', async (env) => {
    for (const s of STUDENTS) {
      let fetches = 0;
      let images = 0;
      for (const r of s.page.requests) {
        const url = new URL(r.url());
        if (r.resourceType() === 'image') {
          images++;
          assert.ok(url.searchParams.get('key'), `${s.key}: ${url.pathname} (an <img>) carries ?key=`);
          continue;
        }
        fetches++;
        const h = await r.allHeaders();
        assert.equal(h['x-brdfa-client'], 'web', `${s.key}: ${r.method()} ${url.pathname} says X-Brdfa-Client: web`);
        if (url.pathname === '/api/auth/join' || (url.pathname === '/api/auth/me' && !h.authorization)) continue;   // before the token
        assert.equal(h.authorization, `Bearer ${s.token}`, `${s.key}: ${r.method()} ${url.pathname} carries the token`);
      }
      assert.ok(fetches > 10 && images >= 1, `${s.key}: ${fetches} API requests and ${images} images seen`);
    }
  }],

  ['the teacher sees both students\' sessions in the Class tab and watches one full size', async (env) => {
    const { page } = await newContext(env, 'teacher', { token: env.adminToken });
    env.teacher = page;
    await page.goto(`${env.server.url}/`);
    await waitForFrame(page, { minVariance: 20, timeout: 60000 });
    assert.equal(await page.locator('#whoami .whoami-role').innerText(), 'teacher');
    await page.click('.tabs [data-tab="tab-class"]');
    for (const s of STUDENTS) {
      const item = page.locator(`#class .class-item[data-session="${s.sid}"]`);
      await item.waitFor({ timeout: 10000 });
      assert.equal(await item.locator('.class-owner').innerText(), s.displayName, `${s.key}'s display name, as text`);
      // Loaded and not blank: the student's render, drawn through the view key.
      await until(`${s.key}'s thumbnail to show a frame`, async () =>
        item.locator('.class-thumb').evaluate((img) => {
          if (!img.complete || !img.naturalWidth) return false;
          const c = document.createElement('canvas');
          c.width = c.height = 32;
          const g = c.getContext('2d');
          g.drawImage(img, 0, 0, 32, 32);
          const d = g.getImageData(0, 0, 32, 32).data;
          const v = [];
          for (let i = 0; i < d.length; i += 4) v.push(d[i], d[i + 1], d[i + 2]);
          const mean = v.reduce((a, x) => a + x, 0) / v.length;
          return v.reduce((a, x) => a + (x - mean) ** 2, 0) / v.length > 20;
        }), 30000);
      const src = await item.locator('.class-thumb').getAttribute('src');
      assert.ok(src.includes(`/api/sessions/${s.sid}/frame`) && /[?&]key=/.test(src), `thumbnail through the view key: ${src}`);
    }
    // Thumbnails are live: a newer one is requested after a while.
    const thumb = page.locator(`#class .class-item[data-session="${STUDENTS[0].sid}"] .class-thumb`);
    const first = await thumb.getAttribute('src');
    await until('a newer thumbnail', async () => (await thumb.getAttribute('src')) !== first, 10000);
    await page.screenshot({ path: join(env.artifacts, 'auth-05-class.png') });

    const s = STUDENTS[0];
    await page.click(`#class .class-item[data-session="${s.sid}"] .class-pick`);
    const big = page.locator('#class .class-watch-img');
    await big.waitFor({ state: 'visible' });
    const width = (await admin(env, 'GET', `/api/sessions/${s.sid}/scene`)).render.width;
    await until('the watched stream at full size', async () =>
      big.evaluate((img, width) => img.naturalWidth === width, width), 30000);
    const src = await big.getAttribute('src');
    assert.ok(src.includes(`/api/sessions/${s.sid}/stream`) && /[?&]key=/.test(src), `the stream through the view key: ${src}`);
    await showsText(page, s.displayName, '#class .class-watch-name');
    await page.screenshot({ path: join(env.artifacts, 'auth-06-class-watch.png') });
    await assertNoInjection(env);
  }],

  ['forms posted from other origins change nothing (403 cross_site)', async (env) => {
    const before = { sessions: await sessionIds(env), codes: await joinCodeIds(env), users: await userNames(env) };
    const forms = [
      { path: '/api/sessions', body: '{"objects":[{"mesh":"sphere","brdf":"ggx"}],"x":""}' },
      { path: '/api/auth/join-codes', body: '{"ttl_minutes":60,"x":""}' },
      { path: '/api/auth/join', body: `{"code":"${env.code}","display_name":"forged","x":""}` },
      // Joining needs no token: smuggled past the gate, it would make a user.
      { path: '/api/sessions', smuggle: { method: 'POST', path: '/api/auth/join', body: `{"code":"${env.code}","display_name":"smuggled"}` } },
    ];
    const site = await attackerSite(forgeryPage(env.server.url, forms));
    const problems = [];
    try {
      // Another port on the same host (another origin, same site), and another host (cross-site),
      // opened in the teacher's browser (which holds the admin token for the API's origin).
      for (const origin of [`http://127.0.0.1:${site.port}`, `http://localhost:${site.port}`]) {
        const answers = await submitForgeries(env, env.server.url, env.teacher.context(), origin, forms.length, `forgery from ${origin}`);
        console.log(`FORGERY from ${origin}: ${answers.map((a) => `${a.path} ${a.status}`).join(', ')}`);
        problems.push(...forgeryProblems(answers, forms.length, origin));
      }
    } finally {
      await site.close();
    }
    const after = { sessions: await sessionIds(env), codes: await joinCodeIds(env), users: await userNames(env) };
    if (JSON.stringify(after.sessions) !== JSON.stringify(before.sessions)) problems.push(`sessions ${before.sessions} -> ${after.sessions}`);
    if (JSON.stringify(after.codes) !== JSON.stringify(before.codes)) problems.push(`join codes ${before.codes} -> ${after.codes}`);
    if (JSON.stringify(after.users) !== JSON.stringify(before.users)) problems.push(`users ${before.users} -> ${after.users}`);
    assert.deepEqual(problems, [], 'forged forms: all refused (403 cross_site), nothing changed');
  }],

  ['a token the teacher revokes: the open page asks for a token and stops its stream', async (env) => {
    const s = STUDENTS[0];
    const user = (await admin(env, 'GET', '/api/auth/users')).find((u) => u.user === s.user);
    assert.ok(user && user.tokens.length === 1, `${s.user} has one token`);
    await admin(env, 'DELETE', `/api/auth/users/${encodeURIComponent(s.user)}/tokens/${encodeURIComponent(user.tokens[0].id)}`);
    const { page } = s;
    await page.locator('#auth .auth-token').waitFor({ state: 'visible', timeout: 15000 });
    await showsText(page, 'no longer accepted', '#auth .auth-reason');
    assert.equal(await page.locator('main').isVisible(), false, 'the app is covered');
    await until('the view\'s stream closed', async () => !(await page.locator('#viewer img').getAttribute('src'))?.includes('/stream'));
    await page.screenshot({ path: join(env.artifacts, 'auth-07-revoked.png') });
  }],

  ['sign out revokes the student\'s token; the page asks for one again', async (env) => {
    const s = STUDENTS[1];
    const { page } = s;
    await page.bringToFront();
    page.once('dialog', (d) => d.accept());
    await page.click('#whoami .whoami-logout');
    await page.locator('#auth .auth-token').waitFor({ state: 'visible', timeout: 15000 });
    assert.equal(await page.evaluate(() => localStorage.getItem('brdfa.token')), null, 'the token is forgotten');
    assert.equal((await call(env, 'GET', '/api/auth/me', { token: s.token })).status, 401, 'the token is revoked');
    await assertNoInjection(env);
  }],

  ['no uncaught errors in any page', async (env) => {
    assert.deepEqual(env.pages.flatMap((p) => p.errors), []);
  }],
];

// --auth none: no token protects anything, so the cross-origin gate is all that stops a form.
async function noneModeForgery(env, opt) {
  const server = await startServer(opt.server, opt.root, { args: ['--auth', 'none'] });
  try {
    const ids = async () => (await (await fetch(`${server.url}/api/sessions`)).json()).map((s) => s.id).sort();
    const before = await ids();
    const forms = [
      { path: '/api/sessions', body: '{"objects":[{"mesh":"sphere","brdf":"ggx"}],"x":""}' },
      { path: '/api/sessions', smuggle: { method: 'POST', path: '/api/sessions', body: '{}' } },
    ];
    const site = await attackerSite(forgeryPage(server.url, forms));
    const context = await env.browser.newContext();
    const problems = [];
    try {
      const origin = `http://localhost:${site.port}`;
      const answers = await submitForgeries(env, server.url, context, origin, forms.length, 'none-mode forgery');
      console.log(`FORGERY none mode from ${origin}: ${answers.map((a) => `${a.path} ${a.status}`).join(', ')}`);
      problems.push(...forgeryProblems(answers, forms.length, origin));
    } finally {
      await context.close();
      await site.close();
    }
    const after = await ids();
    if (JSON.stringify(after) !== JSON.stringify(before)) problems.push(`sessions ${before} -> ${after}`);
    assert.deepEqual(problems, [], 'none mode: forged forms refused (403 cross_site), no session made');
  } finally {
    await server.stop();
  }
}

async function main() {
  const opt = args();
  if (!existsSync(CHROMIUM)) {
    console.log(`SKIP: ${CHROMIUM} not found (apt-get install chromium)`);
    process.exit(77);
  }
  if (!existsSync(join(opt.root, 'web', 'node_modules', 'playwright-core'))) {
    console.log('SKIP: web/node_modules has no playwright-core (cd web && npm ci)');
    process.exit(77);
  }
  const help = execFileSync(opt.server, ['--help'], { encoding: 'utf8' });
  if (!help.includes('--auth') || !help.includes('--admin-token-file')) {
    console.log(`FAIL: ${opt.server} has no --auth / --admin-token-file (docs/api.md, Identities)`);
    process.exit(1);
  }
  const require = createRequire(join(opt.root, 'web', 'package.json'));
  const { chromium } = require('playwright-core');
  execFileSync(process.execPath, [join(opt.root, 'web', 'build.mjs')], { stdio: 'inherit' });
  mkdirSync(opt.artifacts, { recursive: true });

  const secrets = mkdtempSync(join(tmpdir(), 'brdfa-auth-'));
  const adminToken = `brdfa_admin_${randomBytes(24).toString('hex')}`;
  const tokenFile = join(secrets, 'admin-token');
  writeFileSync(tokenFile, `${adminToken}\n`, { mode: 0o600 });
  const server = await startServer(opt.server, opt.root, { args: ['--auth', 'tokens', '--admin-token-file', tokenFile] });
  const browser = await chromium.launch({
    executablePath: CHROMIUM,
    headless: true,
    args: ['--no-sandbox', '--disable-dev-shm-usage'],
  });
  const env = { server, browser, adminToken, artifacts: opt.artifacts, contexts: [], pages: [] };
  let failed = 0;
  const run = async (name, fn) => {
    const t = Date.now();
    try {
      await fn();
      console.log(`ok   ${name} (${Date.now() - t} ms)`);
      return true;
    } catch (e) {
      failed++;
      console.log(`FAIL ${name}: ${e.stack || e}`);
      for (const p of env.pages) {
        if (!p.isClosed()) await p.screenshot({ path: join(opt.artifacts, `auth-fail-${name.replace(/\W+/g, '_').slice(0, 60)}-${p.label}.png`) }).catch(() => {});
      }
      return false;
    }
  };
  try {
    for (const [name, fn] of checks) {
      if (!(await run(name, () => fn(env))) && env.fatal) break;   // later checks need what this one set up
    }
  } finally {
    for (const c of env.contexts) await c.close().catch(() => {});
    await server.stop();
    rmSync(secrets, { recursive: true, force: true });
  }
  try {
    await run('none mode: a cross-site form changes nothing (403 cross_site)', () => noneModeForgery(env, opt));
  } finally {
    await browser.close();
  }
  reportAndExit(failed, server, opt.artifacts);
}

main().catch((e) => { console.error(e); process.exit(1); });
