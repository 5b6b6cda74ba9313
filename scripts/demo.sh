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
# The spatial world planned and drawn in 3-D (world.kind: spatial); override with SPATIAL_WORLD=path make demo.
SPATIAL_WORLD="${SPATIAL_WORLD:-config/spatial/panda_table_to_table.yaml}"
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

# Step 1b: a spatial world (world.kind: spatial, a Panda): planned with clew_plan and drawn in 3-D
# with clew_render (the arm along the plan, the object, the scene).
if [[ ! -f "$SPATIAL_WORLD" ]]; then
    not_built+=("spatial world $SPATIAL_WORLD")
else
    echo "demo: clew_plan $SPATIAL_WORLD --output $OUT/spatial_plan.json --seed 0"
    set +e
    "$BIN/clew_plan" "$SPATIAL_WORLD" --output "$OUT/spatial_plan.json" --seed 0 --quiet
    rc=$?
    set -e
    if [[ $rc -eq 0 ]] && "$BIN/clew_render" "$OUT/spatial_plan.json" --world "$SPATIAL_WORLD" -o "$OUT/spatial.png"; then
        echo "demo: the spatial plan drawn in $OUT/spatial.png"
    else
        echo "demo: planning or drawing $SPATIAL_WORLD failed (clew_plan exit $rc)" >&2
        [[ $status -eq 0 ]] && status=1
    fi
fi

# Step 2: the clew_planner node on the default world (no parameter file: it
# serves config/figure1.yaml), recording to $OUT/recordings; a client calls
# for a plan (clew_ros.client), prints the outcome and waits for the playback; then SIGINT stops the
# node (which must exit 0). Works with or without the recorder: the answer
# says where the run was recorded, or why not. Joints move at up to 3 rad/s and
# 12 rad/s^2 in the trajectory (default 1 rad/s, 2 rad/s^2) so that the playback is short.
RECORDINGS="$OUT/recordings"
mkdir -p "$RECORDINGS"
node_pid=""
arm_pid=""
stop_node() {
    if [[ -n "$arm_pid" ]]; then kill -INT "$arm_pid" 2>/dev/null || true; fi
    if [[ -n "$node_pid" ]] && kill -0 "$node_pid" 2>/dev/null; then
        kill -INT "$node_pid" 2>/dev/null || true
        for _ in $(seq 100); do kill -0 "$node_pid" 2>/dev/null || break; sleep 0.1; done
        kill -KILL "$node_pid" 2>/dev/null || true
    fi
}
trap stop_node EXIT

echo "demo: clew_planner --ros-args -p record.directory:=$RECORDINGS -p trajectory.max_velocity:=3.0" \
     "-p trajectory.max_acceleration:=12.0 (log: $OUT/clew_planner.log)"
"$BIN/clew_planner" --ros-args -p "record.directory:=$RECORDINGS" -p trajectory.max_velocity:=3.0 \
    -p trajectory.max_acceleration:=12.0 \
    >"$OUT/clew_planner.log" 2>&1 &
node_pid=$!

echo "demo: python -m clew_ros.client.call_plan: a plan to the default goal through clew_ros.client"
set +e
"$PY" -m clew_ros.client.call_plan --node /clew_planner --timeout 180 --wait-playback | tee "$OUT/plan_call.txt"
rc=${PIPESTATUS[0]}
set -e
case $rc in
    0) echo "demo: the node found a plan" ;;
    1) echo "demo: the node found no plan (see above)" >&2; status=1 ;;
    *) echo "demo: no answer from the node; its log:" >&2; cat "$OUT/clew_planner.log" >&2; status=$rc ;;
esac

kill -INT "$node_pid" 2>/dev/null || true
set +e
wait "$node_pid"
node_rc=$?
set -e
node_pid=""
if [[ $node_rc -ne 0 ]]; then
    echo "demo: clew_planner exited with code $node_rc; its log:" >&2
    cat "$OUT/clew_planner.log" >&2
    [[ $status -eq 0 ]] && status=$node_rc
else
    echo "demo: clew_planner stopped cleanly (SIGINT, exit 0)"
fi

run_id=$(grep -oE 'run [0-9a-f]{32}' "$OUT/plan_call.txt" | head -1 | cut -d' ' -f2 || true)
RUN_DIR="$RECORDINGS/$run_id"
if [[ -n "$run_id" && -f "$RUN_DIR/metadata.yaml" ]]; then
    echo "demo: run recorded in $RUN_DIR"
else
    not_built+=("recording of the node's run")
fi
# The picture: the recorded run drawn (PNG filmstrip and GIF animation).
if [[ -n "$run_id" && -f "$RUN_DIR/metadata.yaml" ]]; then
    if "$BIN/clew_render" "$RUN_DIR" -o "$OUT/plan.png" && "$BIN/clew_render" "$RUN_DIR" -o "$OUT/plan.gif"; then
        echo "demo: picture of the run in $OUT/plan.png and $OUT/plan.gif"
    else
        echo "demo: clew_render failed" >&2
        [[ $status -eq 0 ]] && status=1
    fi
fi
# Replay it for RViz/Foxglove: "$BIN/clew_replay" "$RUN_DIR" --rate 4

# Step 3: the node on the spatial world (the Panda): started in the world file's folder (a node reads the
# world's relative paths, URDF and SRDF, from its working directory; the launch file
# clew_spatial_planner.launch.py makes them absolute instead), a client calls for a plan, the run is recorded
# (the arm's links and /tf in it), then SIGINT stops the node.
if [[ -f "$SPATIAL_WORLD" ]]; then
    SPATIAL_RECORDINGS="$(pwd)/$OUT/recordings_spatial"
    mkdir -p "$SPATIAL_RECORDINGS"
    echo "demo: (cd $(dirname "$SPATIAL_WORLD") && clew_planner --ros-args --params-file $(basename "$SPATIAL_WORLD")" \
         "-p record.directory:=$SPATIAL_RECORDINGS) (log: $OUT/clew_planner_spatial.log)"
    planner="$(pwd)/$BIN/clew_planner"
    (cd "$(dirname "$SPATIAL_WORLD")" && exec "$planner" --ros-args \
        --params-file "$(basename "$SPATIAL_WORLD")" -p "record.directory:=$SPATIAL_RECORDINGS" \
        -p trajectory.max_velocity:=3.0 -p trajectory.max_acceleration:=12.0) \
        >"$OUT/clew_planner_spatial.log" 2>&1 &
    node_pid=$!
    set +e
    "$PY" -m clew_ros.client.call_plan --node /clew_planner --timeout 300 | tee "$OUT/spatial_plan_call.txt"
    rc=${PIPESTATUS[0]}
    set -e
    case $rc in
        0) echo "demo: the node planned the spatial world" ;;
        *) echo "demo: the spatial run failed (exit $rc); the node's log:" >&2
           cat "$OUT/clew_planner_spatial.log" >&2; [[ $status -eq 0 ]] && status=1 ;;
    esac
    kill -INT "$node_pid" 2>/dev/null || true
    set +e
    wait "$node_pid"
    node_rc=$?
    set -e
    node_pid=""
    if [[ $node_rc -ne 0 ]]; then
        echo "demo: the spatial clew_planner exited with code $node_rc" >&2
        [[ $status -eq 0 ]] && status=$node_rc
    fi
    spatial_run=$(grep -oE 'run [0-9a-f]{32}' "$OUT/spatial_plan_call.txt" | head -1 | cut -d' ' -f2 || true)
    if [[ -n "$spatial_run" && -f "$SPATIAL_RECORDINGS/$spatial_run/metadata.yaml" ]]; then
        echo "demo: spatial run recorded in $SPATIAL_RECORDINGS/$spatial_run (open it in Foxglove or RViz)"
        if "$BIN/clew_render" "$SPATIAL_RECORDINGS/$spatial_run" -o "$OUT/spatial_run.gif"; then
            echo "demo: the recorded spatial run drawn in $OUT/spatial_run.gif"
        else
            echo "demo: clew_render failed on the spatial recording" >&2
            [[ $status -eq 0 ]] && status=1
        fi
    else
        not_built+=("recording of the spatial run")
    fi
fi

# Step 4: the closed loop (docs/interface.md section 3c): the Panda's planner plans from the world as it is now
# (state.joint_states, state.points, state.advance), a simulated arm follows each ~/trajectory and publishes
# /joint_states at 50 Hz, and a client asks three pick-and-place goals in a row, each from where the last
# ended, publishing a point cloud of a cube standing on table_a before the second. Each run is drawn, and the
# three pictures side by side are the sequence: $OUT/closed_loop.png.
LOOP_WORLD=config/spatial/panda_table_to_table.yaml
if [[ -f "$LOOP_WORLD" ]]; then
    LOOP="$OUT/closed_loop"
    mkdir -p "$LOOP"
    arm_joints=$("$PY" - "$LOOP_WORLD" "$LOOP/world.yaml" <<'PYEOF'
import sys
from pathlib import Path

import yaml

from clew_ros.ros.spatial import resolved_parameters
from clew_ros.spatial.world import spatial_world_from_parameters

source, target = Path(sys.argv[1]), Path(sys.argv[2])
parameters = resolved_parameters(source)  # the URDF's and SRDF's paths made absolute
parameters["state"] = {"joint_states": True, "points": True, "advance": True}
target.write_text(yaml.safe_dump({"clew_planner": {"ros__parameters": parameters}}))
world = spatial_world_from_parameters(parameters, source.parent)
print(",".join(f"{n}={v!r}" for n, v in zip(world.robot.joint_names, world.initial.tolist(), strict=True)))
PYEOF
)
    echo "demo: closed loop: clew_planner --params-file $LOOP/world.yaml (state.joint_states, state.points," \
         "state.advance), python -m clew_ros.examples.simulated_arm, python -m clew_ros.examples.pick_and_place_loop"
    "$BIN/clew_planner" --ros-args --params-file "$LOOP/world.yaml" -p "record.directory:=$(pwd)/$LOOP/recordings" \
        -p trajectory.max_velocity:=3.0 -p trajectory.max_acceleration:=12.0 >"$LOOP/clew_planner.log" 2>&1 &
    node_pid=$!
    "$PY" -m clew_ros.examples.simulated_arm --joints "$arm_joints" >"$LOOP/simulated_arm.log" 2>&1 &
    arm_pid=$!
    set +e
    "$PY" -m clew_ros.examples.pick_and_place_loop --summary "$LOOP/runs.json" --obstacle 0.61,0.19,0.12,0.06 \
        0.5,-0.3,0.17,0,0,0.5 0.5,0.3,0.17,0,0,0 0.5,-0.3,0.17,0,0,0 | tee "$LOOP/loop.txt"
    rc=${PIPESTATUS[0]}
    set -e
    set +e
    kill -INT "$arm_pid" 2>/dev/null
    wait "$arm_pid"
    kill -INT "$node_pid" 2>/dev/null
    wait "$node_pid"
    node_rc=$?
    set -e
    node_pid=""
    arm_pid=""
    if [[ $rc -ne 0 || $node_rc -ne 0 ]]; then
        echo "demo: the closed loop failed (client exit $rc, node exit $node_rc); the node's log:" >&2
        cat "$LOOP/clew_planner.log" >&2
        [[ $status -eq 0 ]] && status=1
    else
        pictures=()
        for run in $("$PY" -c 'import json, sys; print(" ".join(r["recording"] for r in json.load(open(sys.argv[1]))))' \
                     "$LOOP/runs.json"); do
            "$BIN/clew_render" "$run" -o "$LOOP/$(basename "$run").png" && pictures+=("$LOOP/$(basename "$run").png")
        done
        if "$PY" - "$OUT/closed_loop.png" "${pictures[@]}" <<'PYEOF'
import sys

from PIL import Image

frames = [Image.open(path).convert("RGB") for path in sys.argv[2:]]
strip = Image.new("RGB", (sum(f.width for f in frames), max(f.height for f in frames)), "white")
x = 0
for frame in frames:
    strip.paste(frame, (x, 0))
    x += frame.width
strip.save(sys.argv[1])
PYEOF
        then
            echo "demo: the closed loop's three runs, in order, in $OUT/closed_loop.png"
        else
            echo "demo: drawing the closed loop failed" >&2
            [[ $status -eq 0 ]] && status=1
        fi
    fi
fi

if [[ ${#not_built[@]} -gt 0 ]]; then
    echo "demo: not built yet: $(IFS=','; echo "${not_built[*]}" | sed 's/,/, /g')"
fi
exit "$status"
