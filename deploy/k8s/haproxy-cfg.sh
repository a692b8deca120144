#!/bin/sh
# Writes the HAProxy configuration of the Kubernetes deployment (deploy/k8s/haproxy.cfg) for N
# replicas of the StatefulSet brdfa (default 3), through deploy/haproxy/make-haproxy-cfg.sh:
#   sh deploy/k8s/haproxy-cfg.sh 5 > deploy/k8s/haproxy.cfg
# Replica i is the pod brdfa-i; its --replica tag is its pod name (BRDFA_REPLICA). HAProxy's own
# resolver reads only the name servers of resolv.conf, never its search domains, so each pod is
# named in full: brdfa-i.brdfa.<namespace>.svc.<cluster domain>, the namespace and domain
# filled in by HAProxy from its environment (POD_NAMESPACE, CLUSTER_DOMAIN; haproxy.yaml).
set -eu
n="${1:-3}"
case "$n" in ''|*[!0-9]*) echo "usage: $0 [REPLICAS]" >&2; exit 2 ;; esac
set --
i=0
while [ "$i" -lt "$n" ]; do
  # shellcheck disable=SC2016
  set -- "$@" "brdfa-$i=\"brdfa-$i.brdfa.\${POD_NAMESPACE}.svc.\${CLUSTER_DOMAIN}:8080\""
  i=$((i + 1))
done
echo "# deploy/k8s/haproxy-cfg.sh $n: the StatefulSet brdfa's $n replicas (regenerate when scaling)"
# replica-gone.http (a copy of deploy/haproxy's: kustomize reads only this folder) is mounted
# beside haproxy.cfg from the same ConfigMap.
exec sh "$(dirname "$0")/../haproxy/make-haproxy-cfg.sh" --dns --bind :8080 \
  --gone-file /usr/local/etc/haproxy/replica-gone.http "$@"
