# A frozen aprt (SIGSTOP) stops petting /dev/watchdog: softdog resets the VM.
. /hil/lib.sh
echo "# expect: reset"
sed 's/LOOP/true/' /hil/watchdog.yaml > /tmp/wd.yaml
/aprt/bin/aprt run --config /tmp/wd.yaml > /tmp/run.txt 2>&1 &
run=$!
sleep 3
kill -0 $run; check "aprt runs with the watchdog open" [ $? -eq 0 ]
kill -STOP $run
echo "# aprt stopped; waiting for the watchdog (2 s)"
sleep 20
not_ok "the VM was not reset 20 s after aprt froze"
done_testing
