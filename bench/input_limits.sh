#!/usr/bin/env bash
# Hostile-input timings of the loader (issue 12, docs/reliability.md "## Input").
# Generates the inputs in a temporary directory and times `capdyn check` on
# each (wall seconds, exit status, first 160 characters of stderr).
# Usage: bench/input_limits.sh [CAPDYN_BINARY]   (default build/capdyn)
# Optional: STACK_KB=256 runs each check with `ulimit -s 256`.
set -uo pipefail
bin=$(readlink -f "${1:-build/capdyn}")
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cd "$tmp"

body='[simulation]
duration = 0.01
[[system]]
name = "ball"
mass = 1.0
inertia = [0.1, 0.1, 0.1]'

# 1. a chain of 200 includes (each file includes the next)
mkdir chain
n=200
for i in $(seq 0 $((n - 1))); do
  echo "include = [\"c$((i + 1)).toml\"]" > chain/c$i.toml
  echo "title = \"c$i\"" >> chain/c$i.toml
done
echo "$body" > chain/c$n.toml

# 2. 18 files, each including the next twice
mkdir twice
for i in $(seq 0 16); do
  echo "include = [\"t$((i + 1)).toml\", \"t$((i + 1)).toml\"]" > twice/t$i.toml
done
echo "$body" > twice/t17.toml

# 3. a dotted key of 20 000 names (60 KB) and a table header of as many
python3 - <<'PY'
body = open("chain/c200.toml").read()
keys = ".".join("a" for _ in range(20000))
open("dotted.toml", "w").write(body + "\n" + keys + " = 1\n")
open("header.toml", "w").write(body + "\n[" + keys + "]\nx = 1\n")
open("nested.toml", "w").write(body + "\nx = " + "[" * 20000 + "]" * 20000 + "\n")
PY

# 4. contact slots: N check points x one pair; many identical pairs
mkcp() {  # $1 = number of check points, $2 = number of identical pairs
  python3 - "$1" "$2" > "cp_$1_$2.toml" <<'PY'
import sys
n, p = int(sys.argv[1]), int(sys.argv[2])
print("[simulation]\nduration = 0.01\n")
print('[[system]]\nname = "a"\nmass = 1.0\ninertia = [0.1, 0.1, 0.1]')
print("checkpoints = [" + ", ".join("[%g, 0, 0, 0.01]" % (i * 1e-6) for i in range(n)) + "]")
print('[[target]]\nname = "t"\nmass = 1.0\ninertia = [0.1, 0.1, 0.1]\nposition = [5, 0, 0]')
print('shape = { type = "sphere", radius = 0.5 }')
for _ in range(p):
    print('[[pair]]\ncheckpoints = "a"\nshape = "t"')
PY
}
mkcp 100000 1
mkcp 10000 1000
# 1 000 000 check points: two systems of 500 000 in two included files
# (one file may have 16 MiB)
python3 - <<'PY'
for s in ("a", "b"):
    with open("million_%s.toml" % s, "w") as f:
        f.write('[[system]]\nname = "%s"\nmass = 1.0\ninertia = [0.1, 0.1, 0.1]\n' % s)
        f.write("checkpoints = [" + ", ".join("[%d, 0, 0, 0]" % i for i in range(500000)) + "]\n")
with open("million.toml", "w") as f:
    f.write('include = ["million_a.toml", "million_b.toml"]\n[simulation]\nduration = 0.01\n')
    f.write('[[target]]\nname = "t"\nmass = 1.0\ninertia = [0.1, 0.1, 0.1]\nposition = [0, 0, -5]\n')
    f.write('shape = { type = "sphere", radius = 0.5 }\n')
    f.write('[[pair]]\ncheckpoints = "a"\nshape = "t"\n[[pair]]\ncheckpoints = "b"\nshape = "t"\n')
PY

# 5. duration = 1e300
printf '%s\n' "$body" | sed 's/duration = 0.01/duration = 1e300/' > long.toml

run() {
  local name=$1; shift
  local t0 t1 rc err
  t0=$(date +%s.%N)
  if [ -n "${STACK_KB:-}" ]; then
    err=$( (ulimit -s "$STACK_KB"; timeout 120 "$bin" check "$@") 2>&1 >/dev/null); rc=$?
  else
    err=$(timeout 120 "$bin" check "$@" 2>&1 >/dev/null); rc=$?
  fi
  t1=$(date +%s.%N)
  printf '%-28s %8.3f s  exit %3d  %s\n' "$name" "$(echo "$t1 - $t0" | bc)" "$rc" "${err:0:160}"
}
run "include chain (200)" chain/c0.toml
run "include twice (18 files)" twice/t0.toml
run "dotted key (20000 names)" dotted.toml
run "table header (20000)" header.toml
run "nested arrays (20000)" nested.toml
run "100000 check points" cp_100000_1.toml
run "10000 cp x 1000 pairs" cp_10000_1000.toml
run "1000000 check points" million.toml
run "duration = 1e300" long.toml
