# qemu-user's block log (-d in_asm,exec,nochain, and page for the load
# address) as the runs of each guest instruction: each translated block's
# instructions are logged once (in_asm), and, unchained, every run of the
# block (exec, by its host code's address). A block translated again (after
# a flush) first hands its runs to its old instructions. Prints "PC RUNS"
# lines and, where the log has qemu's page log, "base START_CODE" (where the
# program was loaded); with -v total=1 only the sum of all runs, the run's
# instructions. Read by frame_fit.sh and arm_profile.sh.
function hand(b,   k, a, i) { k = split(code[b], a, " "); for (i = 1; i <= k; i++) n[a[i]] += runs[b]; runs[b] = 0 }
/^start_code/ { base = $2; next }
/^IN:/ { block = 1; list = ""; next }
block && /^0x[0-9a-f]+: / { list = list " " substr($1, 1, length($1) - 1); next }
/^Trace/ { if (block) { if ($3 in code) hand($3); code[$3] = list; block = 0 } runs[$3]++ }
END {
  for (b in code) hand(b)
  if (total) {
    for (pc in n) sum += n[pc]
    printf "%.0f\n", sum
    exit
  }
  if (base != "") print "base", base
  for (pc in n) print pc, n[pc]
}
