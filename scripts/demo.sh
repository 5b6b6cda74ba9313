#!/usr/bin/env bash
# The demo behind `make demo`: runs every step that is built so far and says
# plainly which steps are not built yet. Outputs go to demo_out/.
#
# Run it through `make demo` (which sets up .venv); run directly, it expects
# .venv to exist already.
set -euo pipefail

cd "$(dirname "${BASH_SOURCE[0]}")/.."

# DDS traffic stays on this machine (interface.md §5).
export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST
export ROS_STATIC_PEERS=
export ROS_DOMAIN_ID="${ROS_DOMAIN_ID:-$(( $$ % 90 + 10 ))}"

PY=.venv/bin/python
BIN=.venv/bin
WORLD=config/figure1.yaml
OUT=demo_out

if [[ ! -x "$PY" ]]; then
    echo "demo: .venv is missing; run 'make demo' instead." >&2
    exit 2
fi

mkdir -p "$OUT"
status=0
not_built=()

echo "demo: ROS_DOMAIN_ID=$ROS_DOMAIN_ID, discovery LOCALHOST, outputs in $OUT/"

# Step 1: offline plan with clew_plan.
if [[ ! -f "$WORLD" ]]; then
    not_built+=("world $WORLD")
elif ! "$PY" -c 'import importlib.util, sys; sys.exit(importlib.util.find_spec("clew_ros.cli.plan") is None)'; then
    not_built+=("clew_plan (clew_ros/cli/plan.py)")
else
    echo "demo: clew_plan $WORLD --output $OUT/plan.json --seed 0"
    set +e
    "$BIN/clew_plan" "$WORLD" --output "$OUT/plan.json" --seed 0
    rc=$?
    set -e
    case $rc in
        0) echo "demo: plan found, written to $OUT/plan.json" ;;
        1) echo "demo: no plan found (see $OUT/plan.json)" >&2; status=1 ;;
        *) echo "demo: clew_plan failed with exit code $rc" >&2; status=$rc ;;
    esac
fi

# TODO(node): start the clew_planner node in the background with
#   "$BIN/clew_planner" --ros-args --params-file "$WORLD" -r __node:=clew_planner
#   and stop it (by its pid) on exit.
# TODO(client): call ~/plan (std_srvs/srv/Trigger) and print the response.
# TODO(recording): show the run's rosbag2 directory under $OUT/recordings/
#   (record.directory) and check it with clew_replay.
# TODO(render): "$BIN/clew_render" the plan / recording to $OUT/plan.png.
not_built+=("clew_planner node + service call" "recording" "clew_replay" "clew_render")

echo "demo: not built yet: $(IFS=','; echo "${not_built[*]}" | sed 's/,/, /g')"
exit "$status"
