#!/bin/bash
# touch.c's rounds after 8 s pauses, 4 KiB pages and huge pages, with the guest's free page
# reporting as the VM boots it (page_reporting_order 9: free 2 MiB blocks go back to the host)
# and with it raised past any block the kernel has (11: nothing reported). Run as root; the
# order is put back as it was.
set -euo pipefail
cd "$(dirname "$0")"
knob=/sys/module/page_reporting/parameters/page_reporting_order
was=$(cat "$knob")
trap 'echo "$was" > "$knob"' EXIT
cc -O2 -o /tmp/touch touch.c
for order in "$was" 11; do
  echo "$order" > "$knob"
  /tmp/touch 400 2 huge > /dev/null  # memory reported before the change comes back first
  for pages in 4k huge 4k huge; do
    sleep 8
    printf 'order %s %-4s 400 MiB: ' "$order" "$pages"
    if [[ $pages == huge ]]; then /tmp/touch 400 3 huge; else /tmp/touch 400 3; fi
  done
done
