// Replicas of brdfa-server on loopback ports sharing one data folder, with Debian's HAProxy in
// front, configured by deploy/haproxy/make-haproxy-cfg.sh: what the topology tests start, call
// and stop. Every request is logged with the replica that answered (X-Brdfa-Replica).
import { spawn, execFileSync } from 'node:child_process';
import { mkdtempSync, rmSync, writeFileSync, existsSync } from 'node:fs';
import { createServer } from 'node:net';
import { tmpdir } from 'node:os';
import { join } from 'node:path';

export const haproxyBinary = ['/usr/sbin/haproxy', '/usr/bin/haproxy'].find((p) => existsSync(p));

export const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

export async function waitFor(pred, ms, step = 100) {
  const end = Date.now() + ms;
  while (Date.now() < end) { if (await pred()) return true; await sleep(step); }
  return false;
}

// Named checks; `failures` counts the failed ones.
export function makeChecks() {
  const checks = { failures: 0 };
  checks.check = (ok, what) => {
    console.log(`${ok ? 'ok  ' : 'FAIL'} ${what}`);
    if (!ok) checks.failures += 1;
    return ok;
  };
  return checks;
}

function freePort() {
  return new Promise((res, rej) => {
    const s = createServer();
    s.once('error', rej);
    s.listen(0, '127.0.0.1', () => { const { port } = s.address(); s.close(() => res(port)); });
  });
}

// `checks` (makeChecks) records a request that reached the wrong replica.
export function makeCluster({ root, serverBinary, checks, prefix = 'brdfa-topology-' }) {
  const { check } = checks;
  const dataDir = mkdtempSync(join(tmpdir(), prefix));
  const children = [];
  const requestLog = [];
  const cluster = { dataDir, requestLog, replicas: {} };

  function startProcess(name, cmd, argv) {
    const proc = spawn(cmd, argv, { stdio: ['ignore', 'pipe', 'pipe'] });
    const entry = { name, proc, log: '', exited: null };
    const keep = (d) => { entry.log = (entry.log + d).slice(-200000); };
    proc.stdout.on('data', keep);
    proc.stderr.on('data', keep);
    proc.on('exit', (code, signal) => { entry.exited = { code, signal }; });
    children.push(entry);
    return entry;
  }

  // A replica tagged `tag` on a free port; `extra`: more server flags.
  cluster.startReplica = async (tag, extra = []) => {
    const r = startProcess(tag, serverBinary, [
      '--port', '0', '--root', root, '--data-dir', dataDir, '--replica', tag, '--drain-seconds', '4',
      '--idle-timeout', '60', '--max-memory', '2048', ...extra,
    ]);
    for (let i = 0; i < 600; i++) {
      const m = r.log.match(/listening on (http:\/\/\S+)/);
      if (m) { r.url = m[1]; cluster.replicas[tag] = r; return r; }
      if (r.exited) break;
      await sleep(50);
    }
    throw new Error(`replica ${tag} did not start:\n${r.log}`);
  };

  // HAProxy in front of the started replicas; resolves with the balancer's base URL once it
  // answers /api/ready and every replica had time to enter the pool.
  cluster.startBalancer = async () => {
    const tags = Object.keys(cluster.replicas);
    const port = await freePort();
    const cfgArgs = ['--bind', `127.0.0.1:${port}`, ...tags.map((t) => `${t}=${new URL(cluster.replicas[t].url).host}`)];
    const cfg = execFileSync(join(root, 'deploy/haproxy/make-haproxy-cfg.sh'), cfgArgs, { encoding: 'utf8' });
    const cfgPath = join(dataDir, 'haproxy.cfg');
    writeFileSync(cfgPath, cfg);
    console.log(`haproxy on 127.0.0.1:${port}; replicas ${tags.map((t) => `${t}=${cluster.replicas[t].url}`).join(' ')}`);
    cluster.balancer = startProcess('haproxy', haproxyBinary, ['-db', '-f', cfgPath]);
    const base = `http://127.0.0.1:${port}`;
    check(await waitFor(async () => {
      try { return (await fetch(`${base}/api/ready`)).status === 200; } catch { return false; }
    }, 15000), 'the balancer answers /api/ready');
    await sleep(1500);  // every replica up in the pool before work is spread
    return base;
  };

  // One request, logged with the replica that answered. `expect`: the replica it must reach;
  // `token`: sent as a bearer token.
  cluster.call = async (base, method, path, { json, text, expect, label, token, headers = {} } = {}) => {
    const init = { method, headers: { ...headers } };
    if (token) init.headers.authorization = `Bearer ${token}`;
    if (json !== undefined) { init.body = JSON.stringify(json); init.headers['content-type'] = 'application/json'; }
    if (text !== undefined) { init.body = text; init.headers['content-type'] = 'text/plain'; }
    const res = await fetch(base + path, init);
    const body = await res.text();
    const replica = res.headers.get('x-brdfa-replica') ?? '(balancer)';
    const line = `${method.padEnd(6)} ${path.padEnd(58)} -> ${res.status} served by ${replica}` +
      (expect ? ` (expected ${expect})` : '');
    console.log(`  ${line}`);
    requestLog.push(line);
    if (expect) check(replica === expect, `${label ?? `${method} ${path}`} reached its session's replica ${expect}`);
    let parsed = null;
    try { parsed = JSON.parse(body); } catch { /* not JSON */ }
    return { status: res.status, replica, body, json: parsed };
  };

  // Reads a multipart PNG stream, counting its frames, until stop(); `query`: e.g. "?key=K".
  cluster.openStream = (base, id, { query = '', token } = {}) => {
    const controller = new AbortController();
    const state = { frames: 0, replica: null, status: 0, ended: false };
    const marker = Buffer.from('Content-Type: image/png');
    state.done = (async () => {
      try {
        const headers = token ? { authorization: `Bearer ${token}` } : {};
        const res = await fetch(`${base}/api/sessions/${id}/stream${query}`, { signal: controller.signal, headers });
        state.status = res.status;
        state.replica = res.headers.get('x-brdfa-replica');
        const reader = res.body.getReader();
        let tail = Buffer.alloc(0);
        for (;;) {
          const { value, done } = await reader.read();
          if (done) break;
          const chunk = Buffer.concat([tail, Buffer.from(value)]);
          let at = 0;
          for (;;) {
            const i = chunk.indexOf(marker, at);
            if (i < 0) break;
            state.frames += 1;
            at = i + marker.length;
          }
          tail = chunk.subarray(Math.max(at, chunk.length - marker.length));
        }
      } catch { /* aborted or cut */ }
      state.ended = true;
    })();
    state.stop = () => controller.abort();
    return state;
  };

  // Stops everything, prints the logs when `failed`, removes the data folder.
  cluster.stop = async (failed) => {
    for (const c of children) if (c.exited === null) c.proc.kill('SIGTERM');
    await sleep(300);
    for (const c of children) {
      if (c.exited === null) await waitFor(() => c.exited !== null, 8000);
      if (c.exited === null) c.proc.kill('SIGKILL');
      if (failed) console.log(`---- ${c.name} log tail ----\n${c.log.slice(-3000)}`);
    }
    rmSync(dataDir, { recursive: true, force: true });
  };
  // Runs `scenario`, then stops everything and exits: 0 when every check passed.
  cluster.run = async (scenario) => {
    let exitCode = 1;
    try {
      await scenario();
      exitCode = checks.failures === 0 ? 0 : 1;
      console.log(`\n${requestLog.length} requests logged; ${checks.failures} failed check(s)`);
    } catch (e) {
      console.log(`FAIL ${e.stack}`);
    } finally {
      await cluster.stop(exitCode !== 0);
    }
    process.exit(exitCode);
  };
  return cluster;
}

// A scene small enough to stream from many sessions at once.
export const smallScene = (seed) => ({
  environment: { name: 'furnace' },
  objects: [{ mesh: 'sphere', brdf: 'lambert', params: { Kd: [0.5, 0.5, 0.5] } }],
  render: { width: 48, height: 48, samples_per_frame: 1, max_samples: 1048576, seed },
});
