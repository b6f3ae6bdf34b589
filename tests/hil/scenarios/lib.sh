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
