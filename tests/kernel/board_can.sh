#!/usr/bin/env bash
# Runs inside the kernel rig: the board's CAN port (BoardCanPort) on vcan0, or on the two emulated Kvaser PCI
# controllers (run-in-guest --kvaser: can0 and can1 on one emulated bus, up at 1 Mbit/s), can-utils and iproute2
# as the peers.
# usage: board_can.sh BIN_DIR vcan|kvaser
set -uo pipefail
bin=$1 kind=$2
case $kind in
  vcan) export LEVER_CAN_A=vcan0 LEVER_CAN_B=vcan0 tags='[bus],[vcan]' ;;
  kvaser)
    export LEVER_CAN_A=can0 LEVER_CAN_B=can1 tags='[bus],[kvaser]'
    for ifc in can0 can1; do
      ip -details link show "$ifc" | grep -q 'bitrate 1000000' || { echo "FAILED: $ifc is not at 1 Mbit/s" >&2; exit 1; }
    done
    ;;
  *) echo "usage: board_can.sh BIN_DIR vcan|kvaser" >&2; exit 2 ;;
esac
"$bin/lever_tests_board_can" "$tags" --durations yes
