#!/usr/bin/env bash
# Two keel-net-bench processes on loopback DDS: node 2 echoes, node 1 sends 64 B, 64 KiB and
# 16 MiB envelopes and requires every echo back intact (ping exits non-zero otherwise); then
# the same with the bare libddsc floor (bare-ping, bare-pong).
# Usage: two_processes.sh PATH/TO/keel-net-bench
set -euo pipefail
bench="$1"
domain=$(( 151 + $$ % 50 ))  # gtest DDS tests use 1..150 (domain_id_for)
"$bench" pong --domain "$domain" --duration 120 2>/dev/null &
pong=$!
trap 'kill "$pong" 2>/dev/null || true; wait "$pong" 2>/dev/null || true' EXIT
out="$("$bench" ping --domain "$domain" --sizes 64,65536,16777216 --rounds-small 20 \
  --rounds-large 2 --wire-messages 50)"
echo "$out"
grep -q '"payload_bytes": 16777216, "kind": "large", "topic": "KeelLarge", "rounds": 2, "timeouts": 0' <<<"$out"

# The bare libddsc floor of the latency benchmark (bench-security): the same round trips
# without Keel's code; bare-ping exits non-zero if a round trip gets no echo.
kill "$pong" 2>/dev/null || true
wait "$pong" 2>/dev/null || true
"$bench" bare-pong --domain "$domain" --duration 120 2>/dev/null &
pong=$!
out="$("$bench" bare-ping --domain "$domain" --sizes 64,65536 --rounds 20)"
echo "$out"
grep -q '"history": "keep-all"' <<<"$out"
grep -q '"payload_bytes": 65536, "rounds": 20' <<<"$out"
grep -q '"timeouts": 0' <<<"$out"
