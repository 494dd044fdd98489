#!/bin/bash
# The container's HEALTHCHECK (installed as /usr/local/bin/photond-healthcheck): GET /healthz on
# the daemon with nothing but bash (its /dev/tcp), so the image needs no curl. Exits 0 on a
# 200 answer, 1 otherwise; Docker's --timeout ends it if the daemon does not answer.
#
#   photond-healthcheck [PORT] [PATH]      (defaults: 8080, /healthz; /readyz for readiness)
#
# Checked by tests/deploy/check_deploy.py, which runs it against a started daemon (200 -> 0)
# and against a closed port (-> 1).
set -u
port=${1:-8080}
path=${2:-/healthz}
exec 3<>"/dev/tcp/127.0.0.1/$port" 2>/dev/null || exit 1
printf 'GET %s HTTP/1.0\r\nHost: localhost\r\n\r\n' "$path" >&3 || exit 1
IFS= read -r status <&3 || exit 1
case "$status" in
    "HTTP/1."?" 200 "*) exit 0 ;;
    *) exit 1 ;;
esac
