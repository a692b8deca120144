// Sends the latest value only: while a request is in flight, newer values replace each other
// and the last one goes out when it returns. A slider drag produces far more changes than the
// server can answer; this keeps one request in flight and never queues stale ones. (Edits of
// the session scene go through scene-commands.js instead, which composes merge patches.)
// With `merge`, a value waiting to be sent is combined with the newer one (merge(older, newer))
// instead of replaced: for partial patches, where each holds different fields.
export function coalesce(send, merge = (older, newer) => newer) {
  let pending;        // latest value not sent yet
  let has = false;
  let busy = false;
  const pump = async () => {
    while (has) {
      const value = pending;
      has = false;
      busy = true;
      try { await send(value); } catch { /* send() reports its own errors */ }
      busy = false;
    }
  };
  const push = (value) => {
    pending = has ? merge(pending, value) : value;
    has = true;
    if (!busy) pump();
  };
  push.idle = () => !busy && !has;
  push.waiting = () => has;   // a newer value waits: the answer to this one is already stale
  return push;
}
