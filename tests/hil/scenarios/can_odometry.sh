# The vehicle's odometry from its CAN bus (odometry.source can): the
# interface is missing when aprt starts (it retries), then a sender puts the
# example DBC's speed (36 km/h), yaw rate and gear (D) on it at ~50 Hz, with a few
# frames carrying the ECU's invalid code. aprt takes the samples, refuses the
# invalid ones, and the filter gets the vehicle's motion (poses stop being
# flagged no-odometry).
. /hil/lib.sh
/aprt/bin/aprt run --config /hil/can_odometry.yaml > /tmp/run.txt 2>&1 &
run=$!
for i in $(seq 1 300); do
  grep -q "retrying every second" /tmp/run.txt && break
  sleep 0.1
done
grep -q "interface 'vcan0' not found.*retrying every second" /tmp/run.txt
check "a missing interface at start is reported, not fatal" [ $? -eq 0 ]
ip link add dev vcan0 type vcan && ip link set vcan0 up
# 10.00 m/s = 36.00 km/h = 3600 = 0x0E10, Intel; yaw rate 0.
(
  k=0
  while kill -0 $run 2>/dev/null && [ $k -lt 2000 ]; do
    cansend vcan0 1A1#0000000000000000
    cansend vcan0 1A2#03  # D: the unsigned speed is forward
    if [ $k -ge 20 ] && [ $k -lt 23 ]; then
      cansend vcan0 1A0#FFFF000000000000  # 655.35 km/h: outside the DBC's range
    else
      cansend vcan0 1A0#100E000000000000
    fi
    k=$((k + 1))
    usleep 20000
  done
) &
sender=$!
wait $run
check "aprt run ends cleanly" [ $? -eq 0 ]
kill $sender 2>/dev/null
wait $sender 2>/dev/null
sed 's/^/# run: /' /tmp/run.txt | grep -v "^# run: *[0-9]* " | head -40
line=$(grep "^odometry: can vcan0" /tmp/run.txt)
taken=$(echo "$line" | sed -n 's/.*: \([0-9]*\) samples taken.*/\1/p')
refused=$(echo "$line" | sed -n 's/.* \([0-9]*\) refused.*/\1/p')
echo "$line" | grep -q "ESP_WheelSpeed.VehicleSpeed \[km/h\] + ESP_YawRate.YawRate \[deg/s\], direction TCU_Gear.GearPosition (reverse: 1)"
check "the summary names the interface, the signals, their units and the direction" [ $? -eq 0 ]
[ "${taken:-0}" -ge 5 ]; check "samples taken from the bus ($taken)" [ $? -eq 0 ]
[ "${refused:-0}" -ge 3 ]; check "the invalid codes refused ($refused)" [ $? -eq 0 ]
# Once the samples arrive the filter has the vehicle's motion: later poses
# are no longer flagged no-odometry.
last=$(grep -E "^ *[0-9]+ " /tmp/run.txt | tail -1)
echo "# last pose: $last"
echo "$last" | grep -qv "no-odometry"
check "the last pose has the vehicle's motion (not flagged no-odometry)" [ $? -eq 0 ]
first=$(grep -E "^ *[0-9]+ " /tmp/run.txt | head -1)
echo "$first" | grep -q "no-odometry"
check "the first pose, before the bus came up, had none" [ $? -eq 0 ]
done_testing
