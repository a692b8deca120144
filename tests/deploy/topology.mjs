// The deployed topology, for real: three brdfa-server replicas on loopback ports with
// one shared data folder, Debian's HAProxy in front, configured by
// deploy/haproxy/make-haproxy-cfg.sh. Through the balancer's port it creates six sessions,
// streams from each and patches each; checks that every request reached the replica whose tag
// the session id carries (X-Brdfa-Replica), that a BRDF saved through one replica is listed by
// all, a delete seen by all and an upload usable by all, that /metrics parses with a Prometheus
// text-format parser and its counters move, and that stopping one replica (SIGTERM: it drains) leaves the others streaming
// while its own sessions answer 404. Every request is logged with the replica that served it.
//
//   node tests/deploy/topology.mjs --server build/server/brdfa-server --root .
// Exit 77 (skipped) when haproxy is not installed.
import { readFileSync } from 'node:fs';
import { join, resolve } from 'node:path';
import { execFileSync } from 'node:child_process';
import { createRequire } from 'node:module';
import { haproxyBinary, makeChecks, makeCluster, sleep, smallScene as scene, waitFor } from './cluster.mjs';

const args = Object.fromEntries(
  process.argv.slice(2).reduce((acc, a, i, all) => (a.startsWith('--') ? [...acc, [a.slice(2), all[i + 1]]] : acc), []),
);
const root = resolve(args.root ?? '.');
const serverBinary = resolve(args.server ?? join(root, 'build/server/brdfa-server'));
const require = createRequire(join(root, 'web/package.json'));
const parsePrometheus = require('parse-prometheus-text-format');

if (!haproxyBinary) {
  console.log('haproxy is not installed (docker/install-deps.sh installs it): skipped');
  process.exit(77);
}

const checks = makeChecks();
const { check } = checks;
const cluster = makeCluster({ root, serverBinary, checks });
const { call, openStream, requestLog, replicas } = cluster;

const metricsOf = async (url) => {
  const res = await fetch(`${url}/metrics`);
  const text = await res.text();
  return { families: parsePrometheus(text), text, type: res.headers.get('content-type') };
};
const value = (families, name, labels = {}) => {
  const f = families.find((x) => x.name === name);
  if (!f) return undefined;
  const m = f.metrics.find((x) => Object.entries(labels).every(([k, v]) => (x.labels ?? {})[k] === v));
  if (!m) return undefined;
  return Number(m.value ?? m.count);
};


await cluster.run(async () => {
  const tags = ['r1', 'r2', 'r3'];
  for (const t of tags) await cluster.startReplica(t);
  const base = await cluster.startBalancer();
  const lb = cluster.balancer;

  // The committed example config is the script's output, so it cannot drift from the rule.
  const example = execFileSync(join(root, 'deploy/haproxy/make-haproxy-cfg.sh'),
    ['--bind', '127.0.0.1:8080', '--gone-file', 'deploy/haproxy/replica-gone.http', 'r1=127.0.0.1:8081',
      'r2=127.0.0.1:8082', 'r3=127.0.0.1:8083'], { encoding: 'utf8' });
  check(readFileSync(join(root, 'deploy/haproxy/haproxy.cfg'), 'utf8') === example,
    'deploy/haproxy/haproxy.cfg is what make-haproxy-cfg.sh writes');

  console.log('\n-- six sessions through the balancer');
  const sessions = [];
  for (let i = 0; i < 6; i++) {
    const r = await call(base, 'POST', '/api/sessions', { json: scene(i) });
    check(r.status === 201, `session ${i} created (${r.status} ${r.status === 201 ? '' : r.body})`);
    const id = r.json?.id ?? '';
    const tag = id.split('.')[0];
    check(tag === r.replica && tags.includes(tag), `session id ${id} carries the tag of the replica that made it (${r.replica})`);
    sessions.push({ id, tag });
  }
  const used = new Set(sessions.map((s) => s.tag));
  check(used.size === 3, `new sessions spread over the replicas by load: ${[...used].join(', ')}`);

  const before = {};
  for (const t of tags) before[t] = await metricsOf(replicas[t].url);

  console.log('\n-- a stream from each, a patch to each');
  const streams = sessions.map((s) => openStream(base, s.id));
  check(await waitFor(() => streams.every((st) => st.frames >= 2), 60000), 'every stream delivers frames');
  sessions.forEach((s, i) => {
    check(streams[i].status === 200 && streams[i].replica === s.tag,
      `stream of ${s.id} served by ${streams[i].replica} (expected ${s.tag})`);
  });
  for (const s of sessions) {
    const r = await call(base, 'PATCH', `/api/sessions/${s.id}/scene`,
      { json: { objects: [{ mesh: 'sphere', brdf: 'lambert', params: { Kd: [0.25, 0.5, 0.75] } }] }, expect: s.tag });
    check(r.status === 200, `patch of ${s.id} -> ${r.status}`);
    const st = await call(base, 'GET', `/api/sessions/${s.id}/stats`, { expect: s.tag });
    check(st.status === 200, `stats of ${s.id}`);
  }
  const other = sessions.find((s) => s.tag !== sessions[0].tag);
  const colocated = await call(base, 'POST', `/api/sessions?colocate=${other.id}`, { json: scene(9) });
  check(colocated.status === 201 && colocated.replica === other.tag && colocated.json.id.startsWith(`${other.tag}.`),
    `POST /api/sessions?colocate=${other.id} makes the new session on ${other.tag}`);
  await call(base, 'DELETE', `/api/sessions/${colocated.json.id}`, { expect: other.tag });
  const unknown = await call(base, 'GET', `/api/sessions/${sessions[0].tag}.0000000000000000/stats`, { expect: sessions[0].tag });
  check(unknown.status === 404, 'an id the replica does not hold is 404 from that replica');

  console.log('\n-- one-shot renders and batch jobs spread by load');
  const renders = await Promise.all([0, 1, 2].map((i) => call(base, 'POST', '/api/render',
    { json: { scene: { ...scene(i), render: { width: 32, height: 32 } }, spp: 64, format: 'png' } })));
  check(renders.every((r) => r.status === 200), `three concurrent one-shot renders: ${renders.map((r) => r.status).join(' ')}`);
  const renderReplicas = new Set(renders.map((r) => r.replica));
  check(renderReplicas.size >= 2, `concurrent one-shot renders spread over replicas: ${[...renderReplicas].join(', ')}`);
  const job = await call(base, 'POST', '/api/jobs/validate', { json: { names: ['lambert'] } });
  check(job.status === 202 && job.json?.id?.startsWith(`${job.replica}.job-`), `a batch job's id carries its replica: ${job.json?.id}`);
  let jobDone = false;
  for (let i = 0; i < 100 && !jobDone; i++) {
    const j = await call(base, 'GET', `/api/jobs/${job.json.id}`, { expect: job.replica, label: 'job poll' });
    jobDone = j.status === 200 && j.json?.state === 'done';
    if (!jobDone) await sleep(300);
  }
  check(jobDone, `job ${job.json?.id} polled through the balancer to done`);

  console.log('\n-- the shared data folder');
  const brdf = 'analytic\n::begin parameters\ncolor Kd .5 .5 .5\n::end parameters\n::begin shader\n' +
    'vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return Kd / 3.14159265; }\n::end shader\n';
  const saved = await call(base, 'PUT', '/api/brdfs/topology_shared', { text: brdf });
  check(saved.status === 201 || saved.status === 200, `BRDF saved through the balancer (${saved.status}: ${saved.body.slice(0, 200)})`);
  for (const t of tags) {
    const list = await call(replicas[t].url, 'GET', '/api/brdfs');
    check(JSON.stringify(list.json).includes('"topology_shared"'), `replica ${t} lists the BRDF saved via ${saved.replica}`);
  }
  const preset = await call(base, 'PUT', '/api/brdfs/topology_shared/presets/grey', { json: { Kd: [0.3, 0.3, 0.3] } });
  check(preset.status === 201 || preset.status === 200, `preset saved via ${preset.replica} (${preset.status})`);
  for (const t of tags) {
    const p = await call(replicas[t].url, 'GET', '/api/brdfs/topology_shared/presets/grey');
    check(p.status === 200, `replica ${t} reads the preset saved via ${preset.replica}`);
  }
  const deleter = tags.find((t) => t !== saved.replica);
  const del = await call(replicas[deleter].url, 'DELETE', '/api/brdfs/topology_shared');
  check(del.status === 204, `deleted through replica ${deleter}`);
  for (const t of tags) {
    const got = await call(replicas[t].url, 'GET', '/api/brdfs/topology_shared');
    check(got.status === 404, `replica ${t} no longer has it (${got.status})`);
  }

  // An upload through one replica is a mesh a scene on another may use, without a restart.
  const octahedron = 'v 1 0 0\nv -1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nv 0 0 -1\n' +
    'f 1 3 5\nf 3 2 5\nf 2 4 5\nf 4 1 5\nf 3 1 6\nf 2 3 6\nf 4 2 6\nf 1 4 6\n';
  const form = new FormData();
  form.append('file', new Blob([octahedron], { type: 'text/plain' }), 'octahedron.obj');
  const upRes = await fetch(`${replicas.r1.url}/api/assets`, { method: 'POST', body: form });
  const uploaded = await upRes.json();
  check(upRes.status === 201 && typeof uploaded.id === 'string', `mesh uploaded through r1: ${upRes.status} ${uploaded.id}`);
  for (const t of ['r2', 'r3']) {
    const meshScene = { ...scene(5), objects: [{ mesh: uploaded.id, brdf: 'lambert' }] };
    const r = await call(replicas[t].url, 'POST', '/api/sessions', { json: meshScene });
    check(r.status === 201, `replica ${t} renders r1's new upload ${uploaded.id} (${r.status} ${r.status === 201 ? '' : r.body.slice(0, 160)})`);
    if (r.status === 201) await call(replicas[t].url, 'DELETE', `/api/sessions/${r.json.id}`);
  }

  console.log('\n-- /metrics');
  for (const t of tags) {
    const after = await metricsOf(replicas[t].url);
    check(after.type?.startsWith('text/plain; version=0.0.4'), `${t}: /metrics is the Prometheus text format (${after.type})`);
    const names = after.families.map((f) => f.name);
    for (const want of ['brdfa_sessions', 'brdfa_streams', 'brdfa_samples_rendered_total', 'brdfa_pass_duration_seconds',
      'brdfa_queue_wait_seconds', 'brdfa_compiles_total', 'brdfa_compile_duration_seconds', 'brdfa_rejections_total',
      'brdfa_memory_used_bytes', 'brdfa_memory_budget_bytes', 'brdfa_replica_info'])
      if (!names.includes(want)) check(false, `${t}: /metrics has ${want}`);
    for (const f of after.families) if (!f.help) check(false, `${t}: ${f.name} has help text`);
    const mine = sessions.filter((s) => s.tag === t).length;
    check(value(after.families, 'brdfa_sessions') === mine + 1, `${t}: brdfa_sessions = ${value(after.families, 'brdfa_sessions')} (its ${mine} + default)`);
    check(value(after.families, 'brdfa_streams') === mine, `${t}: brdfa_streams = ${value(after.families, 'brdfa_streams')}`);
    const s0 = value(before[t].families, 'brdfa_samples_rendered_total');
    const s1 = value(after.families, 'brdfa_samples_rendered_total');
    check(s1 > s0, `${t}: samples rendered moved ${s0} -> ${s1}`);
    const p0 = value(before[t].families, 'brdfa_pass_duration_seconds');
    const p1 = value(after.families, 'brdfa_pass_duration_seconds');
    check(p1 > p0, `${t}: pass-time histogram count moved ${p0} -> ${p1}`);
    const c1 = value(after.families, 'brdfa_compiles_total', { result: 'ok' }) +
      value(after.families, 'brdfa_spirv_cache_hits_total', { cache: 'disk' }) +
      value(after.families, 'brdfa_spirv_cache_hits_total', { cache: 'memory' });
    check(c1 > 0, `${t}: programs compiled or read from the shared cache: ${c1}`);
    check(value(after.families, 'brdfa_memory_used_bytes') <= value(after.families, 'brdfa_memory_budget_bytes'),
      `${t}: memory in use within the budget`);
  }
  const rejectedBefore = value((await metricsOf(replicas.r1.url)).families, 'brdfa_rejections_total', { reason: 'not_found' }) ?? 0;
  await call(replicas.r1.url, 'GET', '/api/sessions/r1.ffffffffffffffff/stats');
  const rejectedAfter = value((await metricsOf(replicas.r1.url)).families, 'brdfa_rejections_total', { reason: 'not_found' });
  check(rejectedAfter === rejectedBefore + 1, `a 404 moves brdfa_rejections_total{reason="not_found"} ${rejectedBefore} -> ${rejectedAfter}`);

  console.log('\n-- stopping one replica (SIGTERM: it drains, then exits)');
  const victim = sessions[0].tag;
  const frameCount = () => streams.map((s) => s.frames);
  replicas[victim].proc.kill('SIGTERM');
  check(await waitFor(async () => (await fetch(`${replicas[victim].url}/api/ready`)).status === 503, 3000),
    `${victim} answers /api/ready 503 while draining`);
  const refused = await call(replicas[victim].url, 'POST', '/api/sessions', { json: scene(7) });
  check(refused.status === 503 && refused.json?.error === 'draining', `${victim} refuses a new session: ${refused.status} ${refused.json?.error}`);
  const stillServed = await call(base, 'GET', `/api/sessions/${sessions[0].id}/stats`, { expect: victim });
  check(stillServed.status === 200, `${victim} still answers its own session while draining`);
  // The balancer takes the draining replica out of the pool within its check interval.
  await sleep(2500);
  const during = await call(base, 'POST', '/api/sessions', { json: scene(8) });
  check(during.status === 201 && during.replica !== victim, `a new session during the drain goes elsewhere (${during.replica})`);
  if (during.status === 201) await call(base, 'DELETE', `/api/sessions/${during.json.id}`, { expect: during.replica });
  const victimStreams = streams.filter((_, i) => sessions[i].tag === victim);
  check(await waitFor(() => replicas[victim].exited !== null, 15000), `${victim} exited after its drain`);
  check(replicas[victim].exited?.code === 0, `${victim} exit code ${JSON.stringify(replicas[victim].exited)}`);
  check(victimStreams.every((s) => s.ended), `${victim}'s streams ended with it`);
  const mark = frameCount();
  check(await waitFor(() => streams.every((s, i) => sessions[i].tag === victim || s.frames >= mark[i] + 2), 30000),
    'the other replicas\' sessions keep streaming');
  for (const s of sessions) {
    const r = await call(base, 'GET', `/api/sessions/${s.id}/stats`, s.tag === victim ? {} : { expect: s.tag });
    if (s.tag === victim) {
      check(r.status === 404 && r.json?.error === 'not_found', `a session of the stopped replica is a clear 404 (${r.status} ${r.body.slice(0, 120)})`);
    } else {
      check(r.status === 200, `${s.id} still answers (${r.status})`);
    }
  }
  for (const s of sessions.filter((x) => x.tag !== victim)) {
    const r = await call(base, 'PATCH', `/api/sessions/${s.id}/scene`, { json: { render: { exposure: 0.5 } }, expect: s.tag });
    check(r.status === 200, `patch of ${s.id} after the stop -> ${r.status}`);
  }
  streams.forEach((s) => s.stop());
  await Promise.all(streams.map((s) => s.done));

  console.log('\n-- balancer log (replica = backend/server)');
  console.log(lb.log.split('\n').filter((l) => l.includes('brdfa')).slice(-12).join('\n'));
});
