#!/usr/bin/env bash
# Regenerates the golden bitstreams on purpose, after a deliberate format or
# encoder change: encodes the bundled bunny with default options (version 2,
# 16-bit class tables, the curvature's sign), without the sign (version 2's
# tables against version 1's, the sign apart) and with --format-version 1 (float32 tables: the file
# the golden images are drawn from), and codes version 2's records as version
# 3 (stipple convert: the coded-records bitstream). Review the diff in `stipple info` output
# and say why in the commit message; a changed bunny_v1.spg means the golden
# images need tests/golden/regenerate_images.sh too.
set -euo pipefail
cd "$(dirname "$0")/../.."
stipple=${STIPPLE:-build/release/tools/stipple}
"$stipple" encode data/bunny.ply -o tests/golden/bunny_v2.spg --quiet --no-cut-table
"$stipple" encode data/bunny.ply -o tests/golden/bunny_v2_unsigned.spg --quiet --no-curvature-sign --no-cut-table
"$stipple" encode data/bunny.ply -o tests/golden/bunny_v1.spg --quiet --format-version 1 --no-cut-table
"$stipple" convert tests/golden/bunny_v2.spg -o tests/golden/bunny_v3.spg --format-version 3
"$stipple" info tests/golden/bunny_v2.spg
"$stipple" info tests/golden/bunny_v3.spg
"$stipple" info tests/golden/bunny_v1.spg
