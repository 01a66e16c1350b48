#!/usr/bin/env bash
# Fuzzes every libFuzzer harness for a bounded time under ASan + UBSan
# (clang; every library instrumented): the .spg reader, decoder and client
# (spg), every scan reader — PLY, PCD, LAS, text (scan), the node stream's
# frame reader, StreamReceiver and serial deframer (stream), the node decoder
# alone under every layout the format allows (decoder), the serial line's
# receiving end as the server runs it (serial), the PNG reader (png), the
# server's message handling and per-client state machine (server), the
# client's serial resend logic (resend), --columns and the text layouts
# (columns), a scan encoded and drawn end to end (encode_render). Starts each from
# its small seeds (tests/fuzz/seeds: under a few KB, so a run makes thousands
# of executions a second) and the crashes found before, which are regression
# inputs (tests/fuzz/regressions/HARNESS/, replayed by every build's tests).
# A crash fails the run; its input is kept under build/fuzz/crashes/ — add it
# to tests/fuzz/regressions/HARNESS/ with the fix. Prints each harness's
# executions.
#   FUZZ_SECONDS=60 (per harness) bash .ci/fuzz.sh
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${FUZZ_SECONDS:-60}
build=build/fuzz
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_COMPILER=clang++ -DSTIPPLE_FUZZ=ON -DSTIPPLE_CHECK_RANGES=ON -DSTIPPLE_WERROR=ON \
  -DCMAKE_CXX_FLAGS="-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=all -O1 -g" >/dev/null
harnesses="spg scan stream decoder serial png server resend columns encode_render cut_table"
cmake --build "$build" -j2 --target $(for h in $harnesses; do printf '%s_fuzz ' "$h"; done)
mkdir -p "$build/crashes"
status=0
for harness in $harnesses; do
  corpus=$build/corpus/$harness
  rm -rf "$corpus" && mkdir -p "$corpus"
  case $harness in
    spg) cp tests/fuzz/seeds/tiny.spg tests/fuzz/seeds/tiny_v3.spg "$corpus/"; max_len=4096 ;;
    scan) cp tests/fuzz/seeds/tiny* "$corpus/"; rm -f "$corpus/tiny.spg" "$corpus/tiny_v3.spg"; max_len=4096 ;;
    stream) cp tests/fuzz/seeds/sphere_stream.* "$corpus/"; max_len=8192 ;;
    decoder) cp tests/fuzz/seeds/decoder_* "$corpus/"; max_len=1024 ;;
    serial) cp tests/fuzz/seeds/sphere_stream.cobs "$corpus/"; max_len=16384 ;;
    png) cp tests/fuzz/seeds/tiny.png "$corpus/"; max_len=4096 ;;
    server) cp tests/fuzz/seeds/client_stream.* "$corpus/"; max_len=4096 ;;
    resend) cp tests/fuzz/seeds/sphere_stream.cobs "$corpus/"; max_len=8192 ;;
    columns) cp tests/fuzz/seeds/columns_* tests/fuzz/seeds/tiny.pts tests/fuzz/seeds/tiny.obj tests/fuzz/seeds/tiny.xyz "$corpus/"; max_len=2048 ;;
    encode_render) cp tests/fuzz/seeds/tiny.xyz tests/fuzz/seeds/tiny_ascii.ply tests/fuzz/seeds/tiny.obj "$corpus/"; max_len=2048 ;;
    cut_table) cp tests/fuzz/seeds/cut_table_* "$corpus/"; max_len=8192 ;;
  esac
  [ -d "tests/fuzz/regressions/$harness" ] && cp tests/fuzz/regressions/$harness/* "$corpus/" 2>/dev/null || true
  log=$build/$harness.log
  if ! "$build/tests/${harness}_fuzz" "$corpus" -max_total_time="$seconds" -max_len="$max_len" -timeout=10 \
      -rss_limit_mb=2048 -print_final_stats=1 -artifact_prefix="$build/crashes/$harness-" >"$log" 2>&1; then
    echo "== fuzz $harness: FAILED (input kept in $build/crashes/) =="
    tail -40 "$log"
    status=1
  fi
  runs=$(sed -n 's/^stat::number_of_executed_units: *\([0-9]*\)/\1/p' "$log" | tail -1)
  echo "fuzz $harness: ${runs:-?} executions in ${seconds} s"
done
exit $status
