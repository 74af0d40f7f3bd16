#!/bin/bash
# The layers of lib/: which folders each folder's sources may include. A folder includes only
# folders below it, so a drive kind's protocol never reaches the shared loops (lib/rt), the lift
# rules (lib/lift) or the bus code (lib/can), and no drive kind includes another. The daemon,
# the tools and the tests may include any shared folder, and a kind's only from that kind's own
# tests and tools (the second check below). Usage: check_layers.sh <source dir> <kind>...
# (the drive kinds: LIFTD_DRIVE_KINDS of the top CMakeLists.txt); prints each include that
# breaks the table and exits 1 if there is one.
set -u
src=${1:?usage: check_layers.sh <source dir> <kind>...}
shift
kinds=("$@")
[[ ${#kinds[@]} -gt 0 ]] || { echo "usage: check_layers.sh <source dir> <kind>..."; exit 2; }

# folder -> the folders it may include besides itself (lowest layer first).
declare -A allowed=(
  [common]=""
  [drive]="common"
  [io]="common"
  [log]="common"
  [service]="common log"
  # The lift's record (SQLite on the board's storage): the daemon's io thread feeds it.
  [record]="common log"
  [can]="common io"
  [lift]="common drive"
  # The machine inputs every kind's simulated lift shares; each kind's simulator lives in the
  # kind's folder (lib/<kind>/sim), so lib/sim sits below the kinds.
  [sim]="common drive lift"
  [rt]="common io log can"
  [config]="common drive log"
  [api]="common drive log"
  # What every kind's lift shares on the daemon's io thread, below the kinds' own lifts
  # (lib/<kind>/host).
  [host]="common drive io log service can lift sim rt config api record"
)
# Each drive kind's folder sits on the shared parts and includes no other kind.
for kind in "${kinds[@]}"; do
  allowed[$kind]="common io log can drive lift sim rt config api host"
done
# The drive kinds put together (the configuration schema, the lifts with their commands and
# `sim` actions): the one folder that knows them all, the registry the daemon reads.
allowed[kinds]="common drive log config api host ${kinds[*]}"

status=0
for dir in "$src"/lib/*/; do
  folder=$(basename "$dir")
  if [[ ! -v allowed[$folder] ]]; then
    echo "lib/$folder: not in the layer table of $0; add it with the folders it may include" \
         "(a drive kind: to LIFTD_DRIVE_KINDS of the top CMakeLists.txt)"
    status=1
    continue
  fi
  while IFS= read -r hit; do
    file=${hit%%:*}
    included=$(sed -E 's/.*#include "([a-z0-9_]+)\/.*/\1/' <<<"${hit#*:}")
    [[ $included == "$folder" ]] && continue
    [[ -d $src/lib/$included ]] || continue  # not a lib/ folder (e.g. a system header)
    if [[ " ${allowed[$folder]} " != *" $included "* ]]; then
      echo "${file#"$src"/}: lib/$folder includes lib/$included (allowed: ${allowed[$folder]:-nothing})"
      status=1
    fi
  done < <(grep -rHE '^#include "[a-z0-9_]+/' "$dir" --include='*.hpp' --include='*.cpp' \
             | sed -E 's/^([^:]+):[0-9]*:?/\1:/')
done
[[ $status == 0 ]] && echo "layers ok: every lib/ folder includes only the folders below it"

# Within lib/kinds, one file names the kinds: the registry (every kind's registry_entry.hpp).
registry_status=0
for kind in "${kinds[@]}"; do
  while IFS= read -r hit; do
    rel=${hit#"$src"/}
    [[ ${rel%%:*} == lib/kinds/registry.hpp && $rel == *"\"$kind/registry_entry.hpp\""* ]] && continue
    echo "$rel: lib/kinds reaches a kind through registry.hpp and the kind's registry_entry.hpp only"
    registry_status=1
  done < <(grep -rHE "^#include \"$kind/" "$src"/lib/kinds)
  grep -q "^#include \"$kind/registry_entry.hpp\"" "$src"/lib/kinds/registry.hpp || {
    echo "lib/kinds/registry.hpp: no entry for the drive kind $kind (lib/$kind/registry_entry.hpp)"
    registry_status=1
  }
done
[[ $registry_status == 0 ]] && echo "registry ok: lib/kinds names each kind in registry.hpp only"
[[ $registry_status == 0 ]] || status=1

# Outside lib/, a kind's headers are its own tests' (tests/<kind>/), its tools' (tools/<kind>-*)
# and its benchmarks' (tools/bench/<kind>/); the daemon and every shared test reach a kind through
# the registry (lib/kinds). There is no exception: code that needs two kinds puts each kind's part
# in that kind's folder, behind a header that names none of its types (the API tests' fakes,
# tests/<kind>/api/ on tests/api/fake_backend.hpp; the USS bus of the DCP cycle's benchmark under
# API load, tools/bench/uss/uss_bus.hpp).
own_status=0
for kind in "${kinds[@]}"; do
  while IFS= read -r file; do
    rel=${file#"$src"/}
    case $rel in
      lib/* | tests/"$kind"/* | tools/"$kind"-* | tools/bench/"$kind"/*) continue ;;
    esac
    echo "$rel: includes lib/$kind outside the kind's own folders (tests/$kind, tools/$kind-*," \
         "tools/bench/$kind); reach the kind through lib/kinds"
    own_status=1
  done < <(grep -rlE "^#include \"$kind/" "$src"/daemon "$src"/tests "$src"/tools \
             --include='*.hpp' --include='*.cpp' 2>/dev/null)
done
[[ $own_status == 0 ]] && echo "kinds ok: a kind's headers are included outside lib/ by its own tests and tools only"
[[ $own_status == 0 ]] || status=1

exit $status
