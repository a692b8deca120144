#!/bin/bash
# The image's HEALTHCHECK: GET /api/health on 127.0.0.1:PORT (default 8080) through bash's
# /dev/tcp, so the runtime image needs no curl. Exit 0 on HTTP 200, 1 otherwise. /api/health
# stays 200 while the server drains (SIGTERM); /api/ready is the one that turns 503.
#   bash docker/healthcheck.sh [PORT]
set -u
port="${1:-8080}"
exec 3<>"/dev/tcp/127.0.0.1/$port" || exit 1
printf 'GET /api/health HTTP/1.0\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n' >&3
IFS=' ' read -r -t 5 _ status _ <&3 || exit 1
[ "$status" = 200 ]
