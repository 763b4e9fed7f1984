#!/bin/bash
# One `voxmesh mesh` process at a time on the CT phantom i16 512³ (2 threads, CPU engine), each
# after a 6 s pause, alternating transparent huge pages in madvise mode (the default here, the
# library asks for them) and off. Prints the extract's total and the process's wall time.
# Run as root; it puts /sys/kernel/mm/transparent_hugepage/enabled back to what it was.
set -euo pipefail
was=$(sed -n 's/.*\[\(.*\)\].*/\1/p' /sys/kernel/mm/transparent_hugepage/enabled)
trap 'echo "$was" > /sys/kernel/mm/transparent_hugepage/enabled' EXIT
build/bench/voxmesh-bench --field ct --type i16 --sizes 512 --write-volume /tmp/ct512.nrrd > /dev/null
for round in 1 2 3 4 5; do
  for thp in madvise never; do
    echo "$thp" > /sys/kernel/mm/transparent_hugepage/enabled
    sleep 6
    start=$(date +%s.%N)
    total=$(build/src/cli/voxmesh mesh /tmp/ct512.nrrd --iso 400.5 --backend cpu --threads 2 -o /tmp/ct512.ply --json 2>&1 |
      /usr/bin/python3 -c 'import sys, json; t = sys.stdin.read(); print(json.loads(t[:t.rfind("}") + 1])["times_s"]["total"])')
    end=$(date +%s.%N)
    printf 'round %d thp %-7s extract %.4f s process %.3f s\n' "$round" "$thp" "$total" "$(echo "$end - $start" | bc)"
  done
done
rm -f /tmp/ct512.ply
