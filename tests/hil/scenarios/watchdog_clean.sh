# A clean end closes /dev/watchdog with the magic character: no reset after it.
. /hil/lib.sh
sed 's/LOOP/false/' /hil/watchdog.yaml > /tmp/wd.yaml
/aprt/bin/aprt run --config /tmp/wd.yaml > /tmp/run.txt 2>&1
check "aprt run ends cleanly" [ $? -eq 0 ]
sed 's/^/# run: /' /tmp/run.txt
sleep 4
ok "no reset 4 s after the clean end (watchdog timeout 2 s)"
done_testing
