#!/usr/bin/env bash
# `make demo`: the built-in Cornell box rendered through the daemon, the way a user does it with
# curl. Starts `photond serve` on a free loopback port, submits the job, follows its progress on
# the event stream, saves the EXR and a PNG preview, renders a second view (which finds the photon
# maps in the cache), and stops the daemon.
#
#   deploy/demo.sh [BUILD_DIR] [OUT_DIR]     (defaults: build, out)
set -euo pipefail
build=${1:-build}
out=${2:-out}
photond="$build/server/photond"
[ -x "$photond" ] || { echo "demo: $photond is missing; run make build first" >&2; exit 1; }
command -v curl >/dev/null || { echo "demo: curl is needed" >&2; exit 1; }
mkdir -p "$out"

cache=$(mktemp -d "${TMPDIR:-/tmp}/photond-demo.XXXXXX")  # a fresh cache: photons are traced once
log="$out/photond.log"
pid=""
cleanup() {
    if [ -n "$pid" ] && kill -0 "$pid" 2>/dev/null; then kill -TERM "$pid"; wait "$pid" || true; fi
    rm -rf "$cache"
}
trap cleanup EXIT

say() { printf '\n== %s\n' "$*"; }
show() { printf '$ %s\n' "$*"; }

# 1. The daemon, on a port the system picks; its first line on stdout says where it listens.
say "starting the daemon"
show "$photond serve --listen 127.0.0.1:0 --cache-dir $cache"
"$photond" serve --listen 127.0.0.1:0 --cache-dir "$cache" >"$cache/stdout" 2>"$log" &
pid=$!
url=""
for _ in $(seq 200); do
    url=$(sed -n 's/^listening on //p' "$cache/stdout")
    [ -n "$url" ] && break
    kill -0 "$pid" 2>/dev/null || { echo "demo: the daemon did not start:" >&2; cat "$log" >&2; exit 1; }
    sleep 0.1
done
[ -n "$url" ] || { echo "demo: the daemon did not say where it listens" >&2; exit 1; }
echo "listening on $url (log: $log)"

# 2. Submit the job: Jensen's Cornell box with photon maps and final gathering, 512 x 512.
job='{"scene": {"builtin": "cornell-box"}, "integrator": "photon-map",
      "image": {"width": 512, "height": 512, "spp": 4},
      "photons": {"global": 200000, "caustic": 100000, "seed": 1}, "gather": {"rays": 256}}'
say "submitting the job"
show "curl -s -X POST $url/v1/jobs -H 'Content-Type: application/json' -d '$job'"
response=$(curl -sS -X POST "$url/v1/jobs" -H 'Content-Type: application/json' -d "$job")
id=$(printf '%s\n' "$response" | sed -n 's/^  "id": "\([^"]*\)".*/\1/p' | head -n 1)
[ -n "$id" ] || { echo "demo: the daemon refused the job:" >&2; echo "$response" >&2; exit 1; }
echo "job $id queued"

# 3. Follow it on the Server-Sent Events stream until it ends.
follow() {
    local job_id=$1 event="" data="" pass="" done_tiles total_tiles state shown="" line_end='\n'
    [ -t 1 ] && line_end='\r'  # on a terminal, one line redrawn in place
    show "curl -sN $url/v1/jobs/$job_id/events"
    while IFS= read -r line; do
        case "$line" in
            "event: "*) event=${line#event: } ;;
            "data: "*)
                data=${line#data: }
                case "$event" in
                    progress)
                        pass=$(printf '%s' "$data" | sed -n 's/.*"pass":"\([^"]*\)".*/\1/p')
                        done_tiles=$(printf '%s' "$data" | sed -n 's/.*"tiles_done":\([0-9]*\).*/\1/p')
                        total_tiles=$(printf '%s' "$data" | sed -n 's/.*"tiles_total":\([0-9]*\).*/\1/p')
                        # Each pass, and every tenth of the tiles.
                        local step=$(( total_tiles > 0 ? done_tiles * 10 / total_tiles : 0 ))
                        if [ -n "$pass" ] && [ "$pass/$step" != "$shown" ]; then
                            shown="$pass/$step"
                            printf "  %-18s %4s / %s tiles   $line_end" "${pass:-}" "$done_tiles" "$total_tiles"
                        fi ;;
                    state)
                        state=$(printf '%s' "$data" | sed -n 's/.*"state":"\([^"]*\)".*/\1/p')
                        if [ "$line_end" = '\r' ]; then printf '\n'; fi
                        printf '  state: %s\n' "$state" ;;
                    done | failed | cancelled) printf '  %s\n' "$event" ;;
                esac ;;
        esac
    done < <(curl -sN "$url/v1/jobs/$job_id/events")
}
say "progress"
follow "$id"

# 4. The results.
say "fetching the image"
show "curl -s '$url/v1/jobs/$id/image.exr?wait=true' -o $out/cornell-box.exr"
curl -sS --fail "$url/v1/jobs/$id/image.exr?wait=true" -o "$out/cornell-box.exr"
show "curl -s $url/v1/jobs/$id/preview.png -o $out/cornell-box.png"
curl -sS --fail "$url/v1/jobs/$id/preview.png" -o "$out/cornell-box.png"
curl -sS --fail "$url/v1/jobs/$id" -o "$out/cornell-box.status.json"
echo "wrote $out/cornell-box.exr, $out/cornell-box.png and $out/cornell-box.status.json"

# 5. A second view of the same scene with the same photon settings: its photon maps come from
#    the cache, so its photon pass takes no time.
view='{"scene": {"builtin": "cornell-box"}, "integrator": "photon-map",
       "camera": {"look_from": [2.0, 4.0, 9.0], "look_at": [0.0, 2.0, 0.0], "vfov_deg": 45},
       "image": {"width": 256, "height": 256, "spp": 1},
       "photons": {"global": 200000, "caustic": 100000, "seed": 1}, "gather": {"rays": 256}}'
say "a second view (photon maps from the cache)"
second=$(curl -sS -X POST "$url/v1/jobs" -d "$view" | sed -n 's/^  "id": "\([^"]*\)".*/\1/p' | head -n 1)
curl -sS --fail "$url/v1/jobs/$second/image.exr?wait=true" -o "$out/cornell-box-view2.exr"
curl -sS --fail "$url/v1/jobs/$second/preview.png" -o "$out/cornell-box-view2.png"
status=$(curl -sS "$url/v1/jobs/$second")
cache_state=$(printf '%s\n' "$status" | sed -n 's/^    "cache": "\([a-z]*\)".*/\1/p' | head -n 1)
tracing=$(printf '%s\n' "$status" | sed -n 's/^    "photon_tracing": \([0-9.e-]*\).*/\1/p' | head -n 1)
echo "photon maps: cache ${cache_state:-?}, photon tracing ${tracing:-?} s; wrote $out/cornell-box-view2.exr"

# 6. Stop the daemon (SIGTERM: it finishes what it writes and exits 0).
say "stopping the daemon"
kill -TERM "$pid"
wait "$pid"
pid=""
echo "done"
