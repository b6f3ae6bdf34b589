# TAP helpers for HIL scenarios (busybox sh). Source it; then ok/not_ok/check.
n=0
ok() { n=$((n + 1)); echo "ok $n - $*"; }
not_ok() { n=$((n + 1)); echo "not ok $n - $*"; }
check() {  # check "description" command...
  d="$1"; shift
  if "$@"; then ok "$d"; else not_ok "$d"; fi
}
done_testing() { echo "1..$n"; }
# The number after "key" in a summary line, e.g. field "estimates sent" /tmp/run.txt
field() { sed -n "s/.* \([0-9][0-9]*\) $1.*/\1/p" "$2" | head -1; }

# Poses from `aprt run --config CONFIG` onto vcan0 (with MTU: 16 classic, 72
# FD) into `aprt candump --strict`: every estimate arrives, no E2E error, no
# flagged pose arrives valid.
can_end_to_end() {
  mtu=$1 config=$2
  ip link add dev vcan0 type vcan && ip link set vcan0 mtu "$mtu" && ip link set vcan0 up
  check "vcan0 up with mtu $mtu (SocketCAN in this kernel)" ip link show vcan0
  /aprt/bin/aprt candump --interface vcan0 --timeout 4 --strict > /tmp/dump.txt 2>&1 &
  dump=$!
  sleep 1
  /aprt/bin/aprt run --config "$config" > /tmp/run.txt 2>&1
  check "aprt run ends cleanly" [ $? -eq 0 ]
  wait $dump
  check "candump --strict: no CRC, counter or grouping error" [ $? -eq 0 ]
  sed 's/^/# run: /' /tmp/run.txt; tail -3 /tmp/dump.txt | sed 's/^/# dump: /'
  sent=$(field "estimates sent" /tmp/run.txt)
  got=$(sed -n 's/^summary: [0-9]* frames, \([0-9]*\) estimates.*/\1/p' /tmp/dump.txt)
  poses=$(sed -n 's/.* \([0-9]*\) poses (\([0-9]*\) flagged).*/\1/p' /tmp/run.txt)
  flagged=$(sed -n 's/.* \([0-9]*\) poses (\([0-9]*\) flagged).*/\2/p' /tmp/run.txt)
  valid=$(grep -c ' VALID ' /tmp/dump.txt)
  [ -n "$sent" ] && [ "$sent" -gt 0 ] && [ "$sent" = "$poses" ]
  check "an estimate per pose ($sent of $poses)" [ $? -eq 0 ]
  [ -n "$got" ] && [ "$got" = "$sent" ]
  check "every estimate received and decoded ($got)" [ $? -eq 0 ]
  [ -n "$poses" ] && [ "$valid" -le $((poses - flagged)) ]
  check "no flagged pose arrives as valid ($valid valid, $flagged flagged)" [ $? -eq 0 ]
}
