# vivid frames -> aprt (V4L2 driver, the shipped model) -> DDS, received by
# `aprt ddsdump` inside the VM like a ROS 2 node would; one frame and the
# pose computed for it go out to the host, which recomputes the pose from the
# same bytes (camera_dds.host).
. /hil/lib.sh
check "the shipped model is in the VM" [ -f /aprt/data/shipped.aprt ]
modprobe vivid n_devs=1 node_types=0x1 input_types=0x0
check "vivid capture node /dev/video0" [ -c /dev/video0 ]
/aprt/bin/aprt ddsdump --config /hil/camera_dds.yaml --timeout 60 > /tmp/dds.txt 2>&1 &
dds=$!
sleep 2
/aprt/bin/aprt run --config /hil/camera_dds.yaml --save-frame 2:/tmp/frame.raw > /tmp/run.txt 2>&1 &
run=$!
sleep 40
kill -TERM $run
wait $run
check "aprt run stops cleanly on SIGTERM" [ $? -eq 0 ]
sleep 2
kill -TERM $dds
wait $dds
sed 's/^/# run: /' /tmp/run.txt; head -3 /tmp/dds.txt | sed 's/^/# dds: /'; tail -1 /tmp/dds.txt | sed 's/^/# dds: /'
published=$(sed -n 's/^dds: \([0-9]*\) poses published.*/\1/p' /tmp/run.txt)
received=$(sed -n 's/^summary: \([0-9]*\) poses.*/\1/p' /tmp/dds.txt)
[ "${published:-0}" -ge 1 ]; check "poses published on DDS (${published:-0})" [ $? -eq 0 ]
[ -n "$received" ] && [ "$received" = "$published" ]
check "every published pose received by the subscriber (${received:-none})" [ $? -eq 0 ]
grep -q "^[0-9]*\.[0-9]* map " /tmp/dds.txt; check "samples carry a stamp and frame_id map" [ $? -eq 0 ]
check "frame 2 saved with its pose" sh -c '[ -s /tmp/frame.raw ] && [ -s /tmp/frame.raw.txt ]'
# The frame for the host: base64 lines, then its sidecar.
base64 /tmp/frame.raw | sed 's/^/# frame-b64 /'
sed 's/^/# frame-txt /' /tmp/frame.raw.txt
done_testing
