#!/bin/bash
# One `voxmesh mesh` process at a time on the CT phantom i16 512³ (2 threads, CPU engine), each
# after a 6 s pause, huge pages on and off in turn, five rounds. Prints the extract's total and
# the process's wall time.
#   cli_thp.sh thp: off is transparent huge pages off for the whole machine (root; the setting
#                   is put back as it was);
#   cli_thp.sh env: off is VOXMESH_HUGE_PAGES=off for the process alone.
set -euo pipefail
how=${1:-thp}
knob=/sys/kernel/mm/transparent_hugepage/enabled
if [[ $how == thp ]]; then
  was=$(sed -n 's/.*\[\(.*\)\].*/\1/p' "$knob")
  trap 'echo "$was" > "$knob"' EXIT
fi
build/bench/voxmesh-bench --field ct --type i16 --sizes 512 --write-volume /tmp/ct512.nrrd > /dev/null
for round in 1 2 3 4 5; do
  for pages in on off; do
    env=()
    if [[ $how == thp ]]; then
      if [[ $pages == on ]]; then echo "$was" > "$knob"; else echo never > "$knob"; fi
    else
      env=(VOXMESH_HUGE_PAGES=$pages)
    fi
    sleep 6
    start=$(date +%s.%N)
    total=$(env "${env[@]}" build/src/cli/voxmesh mesh /tmp/ct512.nrrd --iso 400.5 --backend cpu --threads 2 \
      -o /tmp/ct512.ply --json 2>&1 |
      /usr/bin/python3 -c 'import sys, json; t = sys.stdin.read(); print(json.loads(t[:t.rfind("}") + 1])["times_s"]["total"])')
    end=$(date +%s.%N)
    printf 'round %d %s huge pages %-3s extract %.4f s process %.3f s\n' "$round" "$how" "$pages" "$total" "$(echo "$end - $start" | bc)"
  done
done
rm -f /tmp/ct512.ply
