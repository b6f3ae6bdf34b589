# Poses over CAN FD (one 48-byte frame each) on vcan0 with mtu 72, decoded by the receiver's checks.
. /hil/lib.sh
ip link add dev vcan0 type vcan && ip link set vcan0 mtu 72 && ip link set vcan0 up
check "vcan0 up (SocketCAN in this kernel)" ip link show vcan0
/aprt/bin/aprt candump --interface vcan0 --timeout 4 --strict > /tmp/dump.txt 2>&1 &
dump=$!
sleep 1
/aprt/bin/aprt run --config /hil/can_fd.yaml > /tmp/run.txt 2>&1
check "aprt run ends cleanly" [ $? -eq 0 ]
wait $dump
check "candump --strict: no CRC, counter or grouping error" [ $? -eq 0 ]
sed 's/^/# run: /' /tmp/run.txt; tail -3 /tmp/dump.txt | sed 's/^/# dump: /'
sent=$(field "estimates sent" /tmp/run.txt)
got=$(sed -n 's/^summary: [0-9]* frames, \([0-9]*\) estimates.*/\1/p' /tmp/dump.txt)
poses=$(sed -n 's/.* \([0-9]*\) poses (\([0-9]*\) flagged).*/\1/p' /tmp/run.txt)
flagged=$(sed -n 's/.* \([0-9]*\) poses (\([0-9]*\) flagged).*/\2/p' /tmp/run.txt)
valid=$(grep -c ' VALID ' /tmp/dump.txt)
[ -n "$sent" ] && [ "$sent" -gt 0 ] && [ "$sent" = "$poses" ]; check "an estimate per pose ($sent of $poses)" [ $? -eq 0 ]
[ -n "$got" ] && [ "$got" = "$sent" ]; check "every estimate received and decoded ($got)" [ $? -eq 0 ]
[ -n "$poses" ] && [ "$valid" -le $((poses - flagged)) ]; check "no flagged pose arrives as valid ($valid valid, $flagged flagged)" [ $? -eq 0 ]
done_testing
