#!/usr/bin/env bash
# Regenerates the golden bitstream on purpose, after a deliberate format or
# encoder change: encodes the bundled bunny with default options. Review the
# diff in `stipple info` output and say why in the commit message.
set -euo pipefail
cd "$(dirname "$0")/../.."
stipple=${STIPPLE:-build/release/tools/stipple}
"$stipple" encode data/bunny.ply -o tests/golden/bunny_v1.spg --quiet
"$stipple" info tests/golden/bunny_v1.spg
