# Bus trouble: the interface is missing at start (appears later), then goes
# down and up during the run. aprt keeps running, counts it, recovers, and
# the receiver never sees a CRC or counter error.
. /hil/lib.sh
/aprt/bin/aprt run --config /hil/can_paced.yaml > /tmp/run.txt 2>&1 &
run=$!
# The interface appears once aprt has said it is missing (a fixed sleep raced
# with the model's load, which under TCG on a busy host takes seconds).
for i in $(seq 1 300); do
  grep -q "interface 'vcan0' not found" /tmp/run.txt && break
  sleep 0.1
done
ip link add dev vcan0 type vcan && ip link set vcan0 up
# Frames queued in the kernel when the link goes down are lost: the receiver
# sees a counter gap (what E2E is for), never a CRC error or a repeat.
/aprt/bin/aprt candump --interface vcan0 --timeout 3 --strict --tolerate-loss > /tmp/dump.txt 2>&1 &
dump=$!
sleep 2
ip link set vcan0 down
sleep 0.6
ip link set vcan0 up
wait $run
check "aprt run ends cleanly" [ $? -eq 0 ]
wait $dump
check "candump --strict --tolerate-loss: no CRC error or repeated counter across the outage" [ $? -eq 0 ]
sed 's/^/# run: /' /tmp/run.txt; grep -v "^ *[0-9.]*  ctr" /tmp/dump.txt | sed 's/^/# dump: /'
grep -q "interface 'vcan0' not found" /tmp/run.txt; check "missing interface at start reported" [ $? -eq 0 ]
reopened=$(sed -n 's/.*reopened \([0-9]*\).*/\1/p' /tmp/run.txt)
down=$(sed -n 's/.*link down \([0-9]*\).*/\1/p' /tmp/run.txt)
sent=$(field "estimates sent" /tmp/run.txt)
[ "${reopened:-0}" -ge 1 ]; check "reopened once the interface appeared ($reopened)" [ $? -eq 0 ]
[ "${down:-0}" -ge 1 ]; check "link down counted ($down)" [ $? -eq 0 ]
# Counted on the bus, not from a rate: how many poses a TCG VM infers in a
# second depends on the host's load.
before=$(awk '/is down/ {exit} / ctr / {n++} END {print n+0}' /tmp/dump.txt)
[ "${before:-0}" -ge 1 ]; check "estimates received before the outage ($before)" [ $? -eq 0 ]
[ "${sent:-0}" -gt "${before:-0}" ]; check "estimates sent after it ($sent in all)" [ $? -eq 0 ]
tail -2 /tmp/dump.txt | grep -q ' ctr '; check "estimates arrive after the link came back" [ $? -eq 0 ]
done_testing
