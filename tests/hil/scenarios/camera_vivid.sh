# vivid frames -> aprt (V4L2 driver) -> CAN on vcan0 -> aprt candump --strict;
# the camera unplugged while streaming (vivid unbound) and plugged back:
# reported, DEGRADED, frames again after the reopen.
. /hil/lib.sh
modprobe vivid n_devs=1 node_types=0x1 input_types=0x0
check "vivid capture node /dev/video0" [ -c /dev/video0 ]
/aprt/bin/aprt cameras > /tmp/cameras.txt 2>&1
sed 's/^/# cameras: /' /tmp/cameras.txt
grep -q "/dev/video0 .*bus_info 'platform:vivid-000'" /tmp/cameras.txt
check "aprt cameras lists vivid with its bus_info" [ $? -eq 0 ]
ip link add dev vcan0 type vcan && ip link set vcan0 up
/aprt/bin/aprt candump --interface vcan0 --timeout 20 --strict > /tmp/dump.txt 2>&1 &
dump=$!
/aprt/bin/aprt run --config /hil/camera.yaml > /tmp/run.txt 2>&1 &
run=$!
sleep 8
echo vivid.0 > /sys/bus/platform/drivers/vivid/unbind
sleep 4
echo vivid.0 > /sys/bus/platform/drivers/vivid/bind
sleep 8
kill -TERM $run
wait $run
check "aprt run stops cleanly on SIGTERM" [ $? -eq 0 ]
wait $dump
check "candump --strict: no CRC, counter or grouping error" [ $? -eq 0 ]
sed 's/^/# run: /' /tmp/run.txt; tail -2 /tmp/dump.txt | sed 's/^/# dump: /'
captured=$(sed -n 's/^summary: \([0-9]*\) frames captured.*/\1/p' /tmp/run.txt)
sent=$(field "estimates sent" /tmp/run.txt)
[ "${captured:-0}" -ge 10 ]; check "frames captured from V4L2 ($captured)" [ $? -eq 0 ]
[ "${sent:-0}" -ge 3 ]; check "estimates on CAN ($sent)" [ $? -eq 0 ]
got=$(sed -n 's/^summary: [0-9]* frames, \([0-9]*\) estimates.*/\1/p' /tmp/dump.txt)
[ -n "$got" ] && [ "$got" = "$sent" ]; check "every estimate received and decoded ($got)" [ $? -eq 0 ]
grep -q "v4l2: /dev/video0\|v4l2: platform:vivid-000\|v4l2: no capture device" /tmp/run.txt; check "the unplug is reported" [ $? -eq 0 ]
grep -q "state DEGRADED" /tmp/run.txt; check "DEGRADED while the camera is gone" [ $? -eq 0 ]
grep -q "delivers frames again" /tmp/run.txt; check "frames again after the camera returns" [ $? -eq 0 ]
done_testing
