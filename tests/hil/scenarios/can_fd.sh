# Poses as one 48-byte CAN FD frame each on vcan0 (mtu 72), decoded by the receiver's checks.
. /hil/lib.sh
can_end_to_end 72 /hil/can_fd.yaml
done_testing
