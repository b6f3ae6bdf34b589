# Poses as five classic CAN frames each on vcan0 (mtu 16), decoded by the receiver's checks.
. /hil/lib.sh
can_end_to_end 16 /hil/can.yaml
done_testing
