// Identities and ownership behind the balancer: three brdfa-server replicas with --auth tokens on
// one shared data folder, Debian's HAProxy in front. A teacher and two students, each joining
// through a different replica. Checks that every replica knows every token; that a student's
// session, BRDF, preset, upload and job are 404 to the other student on every replica and
// through the balancer; that listings are class-wide (the teacher sees every student's
// sessions, wherever they run, and watches one through its view key); that the per-person
// quotas hold across replicas; that a token revoked on one replica is refused by the others on
// their next request; and that a crashed replica's sessions leave the class list.
//
//   node tests/deploy/topology_auth.mjs --server build/server/brdfa-server --root .
// Exit 77 (skipped) when haproxy is not installed.
import { writeFileSync } from 'node:fs';
import { join, resolve } from 'node:path';
import { haproxyBinary, makeChecks, makeCluster, sleep, smallScene as scene, waitFor } from './cluster.mjs';

const args = Object.fromEntries(
  process.argv.slice(2).reduce((acc, a, i, all) => (a.startsWith('--') ? [...acc, [a.slice(2), all[i + 1]]] : acc), []),
);
const root = resolve(args.root ?? '.');
const serverBinary = resolve(args.server ?? join(root, 'build/server/brdfa-server'));
if (!haproxyBinary) {
  console.log('haproxy is not installed (docker/install-deps.sh installs it): skipped');
  process.exit(77);
}

const checks = makeChecks();
const { check } = checks;
const cluster = makeCluster({ root, serverBinary, checks, prefix: 'brdfa-topology-auth-' });
const { call, replicas } = cluster;
const tags = ['r1', 'r2', 'r3'];
const quotas = { sessions: 2, brdfs: 2, uploads: 1 };

const brdfText = (k) => 'analytic\n::begin parameters\ncolor Kd .5 .5 .5\n::end parameters\n::begin shader\n' +
  `vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return Kd * ${k} / 3.14159265; }\n::end shader\n`;
const octahedron = 'v 1 0 0\nv -1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nv 0 0 -1\n' +
  'f 1 3 5\nf 3 2 5\nf 2 4 5\nf 4 1 5\nf 3 1 6\nf 2 3 6\nf 4 2 6\nf 1 4 6\n';

async function upload(base, token, name) {
  const form = new FormData();
  form.append('file', new Blob([octahedron], { type: 'text/plain' }), name);
  const res = await fetch(`${base}/api/assets`, { method: 'POST', body: form, headers: { authorization: `Bearer ${token}` } });
  const json = await res.json().catch(() => null);
  console.log(`  POST   /api/assets (${name}) -> ${res.status} served by ${res.headers.get('x-brdfa-replica')}`);
  return { status: res.status, json };
}

// The ids of the sessions `token` lists through `base`.
const listed = async (base, token) => {
  const r = await call(base, 'GET', '/api/sessions', { token });
  return r.status === 200 ? r.json : [];
};
const ids = (list) => list.map((s) => s.id).filter((id) => id !== 'default').sort();

await cluster.run(async () => {
  const adminToken = `teacher-${'x'.repeat(24)}-${process.pid}`;
  const adminFile = join(cluster.dataDir, 'admin-token');
  writeFileSync(adminFile, `${adminToken}\n`, { mode: 0o600 });
  const flags = ['--auth', 'tokens', '--admin-token-file', adminFile, '--quota-sessions', String(quotas.sessions),
    '--quota-brdfs', String(quotas.brdfs), '--quota-uploads', String(quotas.uploads)];
  for (const t of tags) await cluster.startReplica(t, flags);
  const base = await cluster.startBalancer();
  const teacher = adminToken;

  console.log('\n-- one join code, students joining through different replicas');
  const code = await call(base, 'POST', '/api/auth/join-codes', { token: teacher, json: {} });
  check(code.status === 201 && typeof code.json?.code === 'string', `the teacher makes a join code (${code.status})`);
  const joinAs = async (tag, name) => {
    const r = await call(replicas[tag].url, 'POST', '/api/auth/join', { json: { code: code.json.code, display_name: name } });
    check(r.status === 201 && r.json?.role === 'student', `${name} joins through ${tag} (${r.status} ${r.json?.user})`);
    return r.json?.token ?? '';
  };
  const alice = await joinAs('r1', 'alice');
  const bob = await joinAs('r2', 'bob');
  for (const t of tags) {
    for (const [name, token, role] of [['alice', alice, 'student'], ['bob', bob, 'student'], ['teacher', teacher, 'teacher']]) {
      const me = await call(replicas[t].url, 'GET', '/api/auth/me', { token });
      check(me.status === 200 && me.json?.user === name && me.json?.role === role, `${t} knows ${name}'s token (${me.status} ${me.json?.user})`);
    }
    const anon = await call(replicas[t].url, 'GET', '/api/sessions');
    check(anon.status === 401, `${t}: no token is 401 (${anon.status})`);
  }

  console.log('\n-- sessions on different replicas');
  const make = async (tag, token, seed) => {
    const r = await call(replicas[tag].url, 'POST', '/api/sessions', { token, json: scene(seed) });
    check(r.status === 201 && r.json?.id?.startsWith(`${tag}.`), `session on ${tag}: ${r.status} ${r.json?.id ?? r.body.slice(0, 160)}`);
    return r.json?.id ?? `${tag}.missing`;
  };
  const a1 = await make('r1', alice, 1);
  const a3 = await make('r3', alice, 2);
  const b2 = await make('r2', bob, 3);
  const tagOf = (id) => id.split('.')[0];
  for (const id of [a1, a3]) {
    for (const [method, path, json] of [['GET', `/api/sessions/${id}`], ['GET', `/api/sessions/${id}/stats`],
      ['GET', `/api/sessions/${id}/frame`], ['PATCH', `/api/sessions/${id}/scene`, { render: { exposure: 2 } }],
      ['DELETE', `/api/sessions/${id}`]]) {
      const r = await call(base, method, path, { token: bob, json, expect: tagOf(id), label: `bob's ${method} ${path}` });
      check(r.status === 404, `bob's ${method} ${path} through the balancer is 404 (${r.status})`);
    }
    for (const t of tags) {
      const r = await call(replicas[t].url, 'GET', `/api/sessions/${id}/stats`, { token: bob });
      check(r.status === 404, `bob's GET of alice's ${id} straight to ${t} is 404 (${r.status})`);
    }
  }
  const stillA1 = await call(base, 'GET', `/api/sessions/${a1}/stats`, { token: alice, expect: 'r1' });
  check(stillA1.status === 200, `alice's ${a1} is untouched (${stillA1.status})`);

  console.log('\n-- listings are class-wide, each sees what is theirs');
  for (const t of tags) {
    const mine = ids(await listed(replicas[t].url, alice));
    check(JSON.stringify(mine) === JSON.stringify([a1, a3].sort()), `${t} lists alice's two sessions, wherever they run: ${mine.join(' ')}`);
    const bobs = ids(await listed(replicas[t].url, bob));
    check(JSON.stringify(bobs) === JSON.stringify([b2]), `${t} lists bob only his: ${bobs.join(' ')}`);
    const all = await listed(replicas[t].url, teacher);
    check(JSON.stringify(ids(all)) === JSON.stringify([a1, a3, b2].sort()), `${t} lists the teacher every student's session: ${ids(all).join(' ')}`);
    const owners = Object.fromEntries(all.map((s) => [s.id, s.owner]));
    check(owners[a1] === 'alice' && owners[a3] === 'alice' && owners[b2] === 'bob', `${t}: with their owners ${JSON.stringify(owners)}`);
    check(all.filter((s) => s.id !== 'default').every((s) => tags.includes(s.replica) && s.id.startsWith(`${s.replica}.`)),
      `${t}: each entry names the replica that holds it`);
  }
  const classList = await listed(replicas.r1.url, teacher);
  const keyOf = (id) => classList.find((s) => s.id === id)?.view_key ?? '';
  // The Class tab's thumbnails and full-size stream: through the balancer, with the view key.
  for (const id of [a1, a3, b2]) {
    const thumb = await fetch(`${base}/api/sessions/${id}/frame?key=${encodeURIComponent(keyOf(id))}`);
    check(thumb.status === 200 && thumb.headers.get('content-type') === 'image/png' && thumb.headers.get('x-brdfa-replica') === tagOf(id),
      `the teacher's thumbnail of ${id}, listed by r1, comes from ${thumb.headers.get('x-brdfa-replica')} (${thumb.status})`);
    await thumb.arrayBuffer();
  }
  const wrongKey = await fetch(`${base}/api/sessions/${a3}/frame?key=${encodeURIComponent(keyOf(b2))}`);
  check(wrongKey.status === 401, `another session's key does not read ${a3} (${wrongKey.status})`);
  const watch = cluster.openStream(base, b2, { query: `?key=${encodeURIComponent(keyOf(b2))}` });
  check(await waitFor(() => watch.frames >= 2, 30000), `the teacher watches bob's ${b2} full size through the balancer (${watch.frames} frames)`);
  watch.stop();
  await watch.done;

  console.log('\n-- per-person quotas across replicas');
  const third = await call(replicas.r2.url, 'POST', '/api/sessions', { token: alice, json: scene(4) });
  check(third.status === 429 && third.json?.quota === 'sessions' && third.json?.used === 2,
    `alice's third session, on r2 where she has none, is 429 sessions used ${third.json?.used} (${third.status})`);
  const bobsSecond = await call(replicas.r1.url, 'POST', '/api/sessions', { token: bob, json: scene(5) });
  check(bobsSecond.status === 201, `bob still gets a session (${bobsSecond.status})`);
  const saves = [];
  for (const [t, name] of [['r1', 'alice/ggx_a'], ['r2', 'alice/ggx_b'], ['r3', 'alice/ggx_c']])
    saves.push(await call(replicas[t].url, 'PUT', `/api/brdfs/${name}`, { token: alice, text: brdfText(saves.length + 1) }));
  check(saves[0].status === 201 && saves[1].status === 201, `alice saves two BRDFs through r1 and r2 (${saves[0].status} ${saves[1].status})`);
  check(saves[2].status === 429 && saves[2].json?.quota === 'brdfs', `her third, through r3, is 429 brdfs (${saves[2].status} ${saves[2].json?.quota})`);
  const bobSave = await call(replicas.r3.url, 'PUT', '/api/brdfs/bob/mine', { token: bob, text: brdfText(7) });
  check(bobSave.status === 201, `bob saves through r3 (${bobSave.status})`);
  const up1 = await upload(replicas.r1.url, alice, 'alice-mesh.obj');
  const up2 = await upload(replicas.r2.url, alice, 'alice-mesh-2.obj');
  check(up1.status === 201, `alice uploads a mesh through r1 (${up1.status})`);
  check(up2.status === 429 && up2.json?.quota === 'uploads', `her second upload, through r2, is 429 uploads (${up2.status} ${up2.json?.quota})`);
  const bobUp = await upload(replicas.r3.url, bob, 'bob-mesh.obj');
  check(bobUp.status === 201, `bob uploads through r3 (${bobUp.status})`);

  console.log('\n-- BRDFs, presets, uploads and jobs are the owner\'s on every replica');
  const preset = await call(replicas.r1.url, 'PUT', '/api/brdfs/alice/ggx_a/presets/warm', { token: alice, json: { Kd: [0.8, 0.4, 0.2] } });
  check(preset.status === 201 || preset.status === 200, `alice saves a preset through r1 (${preset.status})`);
  for (const t of tags) {
    const brdf = await call(replicas[t].url, 'GET', '/api/brdfs/alice/ggx_a', { token: bob });
    check(brdf.status === 404, `${t}: alice/ggx_a is 404 to bob (${brdf.status})`);
    const list = await call(replicas[t].url, 'GET', '/api/brdfs', { token: bob });
    check(!list.body.includes('alice/'), `${t}: bob's list of BRDFs has none of alice's`);
    const p = await call(replicas[t].url, 'GET', '/api/brdfs/alice/ggx_a/presets/warm', { token: bob });
    check(p.status === 404, `${t}: alice's preset is 404 to bob (${p.status})`);
    const write = await call(replicas[t].url, 'PUT', '/api/brdfs/alice/ggx_a', { token: bob, text: brdfText(9) });
    check(write.status === 403 || write.status === 404, `${t}: bob cannot write alice/ggx_a (${write.status})`);
    const seen = await call(replicas[t].url, 'GET', '/api/brdfs/alice/ggx_a', { token: teacher });
    check(seen.status === 200, `${t}: the teacher reads alice/ggx_a (${seen.status})`);
    const meshScene = { ...scene(6), objects: [{ mesh: up1.json?.id, brdf: 'lambert' }] };
    const useIt = await call(replicas[t].url, 'POST', '/api/sessions', { token: bob, json: meshScene });
    check(useIt.status === 404, `${t}: bob's scene naming alice's upload is 404 (${useIt.status} ${useIt.json?.error})`);
    const assets = await call(replicas[t].url, 'GET', '/api/assets', { token: bob });
    check(!assets.body.includes(up1.json?.id ?? 'none'), `${t}: bob's asset list has no upload of alice's`);
    const gone = await call(replicas[t].url, 'DELETE', `/api/assets/${up1.json?.id}`, { token: bob });
    check(gone.status === 404, `${t}: bob's DELETE of alice's upload is 404 (${gone.status})`);
  }
  const unchanged = await call(replicas.r2.url, 'GET', '/api/brdfs/alice/ggx_a', { token: alice });
  check(unchanged.status === 200 && unchanged.json?.source === brdfText(1), `alice/ggx_a is as alice saved it (${unchanged.status})`);
  const share = await call(replicas.r3.url, 'PATCH', '/api/brdfs/alice/ggx_a', { token: alice, json: { shared: true } });
  check(share.status === 200, `alice shares ggx_a through r3 (${share.status})`);
  for (const t of tags) {
    const ok = await waitFor(async () => (await call(replicas[t].url, 'GET', '/api/brdfs/alice/ggx_a', { token: bob })).status === 200, 3000, 250);
    check(ok, `${t}: bob reads the shared alice/ggx_a`);
    const write = await call(replicas[t].url, 'PUT', '/api/brdfs/alice/ggx_a', { token: bob, text: brdfText(9) });
    check(write.status === 403, `${t}: a shared BRDF is still not bob's to write (${write.status})`);
  }
  const job = await call(base, 'POST', '/api/jobs/validate', { token: alice, json: { names: ['alice/ggx_a'] } });
  check(job.status === 202, `alice starts a job through the balancer (${job.status} ${job.json?.id})`);
  const jobId = job.json?.id ?? 'r1.job-0';
  const bobJob = await call(base, 'GET', `/api/jobs/${jobId}`, { token: bob, expect: tagOf(jobId), label: 'bob\'s job poll' });
  check(bobJob.status === 404, `alice's job ${jobId} is 404 to bob (${bobJob.status})`);
  const bobCancel = await call(base, 'DELETE', `/api/jobs/${jobId}`, { token: bob, expect: tagOf(jobId), label: 'bob\'s job cancel' });
  check(bobCancel.status === 404, `bob cannot cancel it (${bobCancel.status})`);
  const teacherJob = await call(base, 'GET', `/api/jobs/${jobId}`, { token: teacher, expect: tagOf(jobId), label: 'teacher\'s job poll' });
  check(teacherJob.status === 200, `the teacher reads it (${teacherJob.status})`);

  console.log('\n-- a token revoked on one replica is refused by every replica');
  const out = await call(replicas.r1.url, 'POST', '/api/auth/logout', { token: alice });
  check(out.status === 204, `alice logs out through r1 (${out.status})`);
  for (const t of tags) {
    const r = await call(replicas[t].url, 'GET', '/api/auth/me', { token: alice });
    check(r.status === 401, `${t} refuses alice's revoked token on its next request (${r.status})`);
  }
  const removed = await call(replicas.r3.url, 'DELETE', '/api/auth/users/bob', { token: teacher });
  check(removed.status === 204, `the teacher removes bob through r3 (${removed.status})`);
  for (const t of tags) {
    const r = await call(replicas[t].url, 'GET', `/api/sessions/${b2}/stats`, { token: bob });
    check(r.status === 401, `${t} refuses the removed bob's token (${r.status})`);
  }
  const kept = await call(base, 'GET', `/api/sessions/${b2}/stats`, { token: teacher, expect: 'r2' });
  check(kept.status === 200, `bob's session stays the teacher's to read (${kept.status})`);

  console.log('\n-- a crashed replica\'s sessions leave the class list');
  replicas.r3.proc.kill('SIGKILL');
  check(await waitFor(() => replicas.r3.exited !== null, 5000), 'r3 is gone (SIGKILL: no drain, no clean-up)');
  const left = await waitFor(async () => !ids(await listed(replicas.r1.url, teacher)).includes(a3), 20000, 1000);
  check(left, `r1 no longer lists ${a3} of the crashed r3`);
  const rest = ids(await listed(replicas.r2.url, teacher));
  check(rest.includes(a1) && rest.includes(b2), `the live replicas' sessions are still listed: ${rest.join(' ')}`);
});
