#!/usr/bin/env bash
# The doc-test runner (`make test` runs it; `make doctest` alone): every shell
# block of README.md and docs/*.md runs, every output it claims is checked,
# every C snippet of docs/embedding.md compiles and runs.
#
#   tests/doctest/run.sh [FILE.md ...]        default: README.md docs/*.md
#
# A fenced block is classified by an HTML comment (invisible when rendered)
# on the line just above its opening fence:
#
#   <!-- doctest -->              run this shell block (bash -e -o pipefail)
#   <!-- doctest timeout=N -->    ... with a time limit of N s (default 120)
#   <!-- doctest exit=N -->       ... which must exit with status N (default 0)
#   <!-- doctest long ... -->     ... taking minutes: run by `make test-long`
#                                 (DOCTEST_LONG=1: only these), listed by
#                                 `make test`
#   <!-- doctest output -->       the block below is what the previous runnable
#                                 block prints (stdout and stderr): each of its
#                                 lines must equal one output line, in order
#                                 (blank lines and surrounding spaces ignored;
#                                 "..." stands for any text, e.g. a wall time)
#   <!-- doctest skip: REASON --> a shell block that cannot run here (Slurm, a
#                                 make target that rebuilds, ...); listed
#   <!-- doctest c HARNESS -->    a C snippet: compiled into
#                                 tests/doctest/HARNESS.c (its file-scope
#                                 definitions there at SNIP_DEFS, its
#                                 statements in main at SNIP_BODY) and run
#
# A shell block (```sh, ```bash, ```shell) without one of these is an error,
# so that a new example cannot escape the tests. The blocks of one file run in
# order in one scratch directory, $BUILD/doctest/NAME/, in which the
# repository's directories appear as symbolic links (so `build/capdyn`,
# `scenarios/...`, `plots/...` work as written) and output files land; the
# binary is the one `make` just built ($BUILD/capdyn, seen as build/capdyn).
# A line of progress comes at least every 20 s.
set -uo pipefail
cd "$(dirname "$0")/../.."
ROOT=$PWD
BUILD=${BUILD:-build}
CC=${CC:-cc}
DEFAULT_TIMEOUT=${DOCTEST_TIMEOUT:-120}
LONG=${DOCTEST_LONG:-0}
[ -x "$BUILD/capdyn" ] || { echo "doctest: $BUILD/capdyn not found; run 'make' first" >&2; exit 1; }
if [ $# -eq 0 ]; then set -- README.md docs/*.md; fi

exec 3>&1   # progress lines, also while a block's output goes to its log
WORK=$ROOT/$BUILD/doctest
rm -rf "$WORK"
mkdir -p "$WORK"

nrun=0 nok=0 nfail=0 nc=0 nskip=0
failures=() skipped=()
t_start=$(date +%s)

# extract FILE.md into $WORK/blocks/NAME/: one file per classified block and
# a manifest "index|line|kind|options"; unmarked shell blocks go to "bad"
extract() { # file dir
    mkdir -p "$2"
    awk -v dir="$2" '
    function trim(s) { sub(/^[ \t]+/, "", s); sub(/[ \t]+$/, "", s); return s }
    BEGIN { n = 0; inb = 0; marker = "" }
    {
        if (!inb && /^[ \t]*```/) {
            info = $0; sub(/^[ \t]*```/, "", info); info = trim(info)
            inb = 1; n++; start = NR
            kind = ""; opts = ""
            if (prev ~ /^<!-- doctest/) {
                m = prev; sub(/^<!-- doctest[ :]*/, "", m); sub(/[ \t]*-->[ \t]*$/, "", m)
                if (m == "") kind = "run"
                else if (m ~ /^output/) kind = "output"
                else if (m ~ /^skip/) { kind = "skip"; opts = m; sub(/^skip:?[ \t]*/, "", opts) }
                else if (m ~ /^c /) { kind = "c"; opts = m; sub(/^c[ \t]+/, "", opts) }
                else if (m ~ /^(long|timeout=|exit=)/) { kind = "run"; opts = m }
                else kind = "unknown:" m
            } else if (info ~ /^(sh|bash|shell)$/) kind = "bad"
            file = dir "/" n
            printf "" > file
            prev = $0
            next
        }
        if (inb && /^[ \t]*```[ \t]*$/) {
            inb = 0; close(file)
            if (kind != "") printf "%d|%d|%s|%s\n", n, start, kind, opts >> (dir "/manifest")
            prev = $0
            next
        }
        if (inb) print >> file
        if ($0 !~ /^[ \t]*$/ || inb) prev = $0
        if (!inb && $0 ~ /^[ \t]*$/) prev = ""
    }' "$1"
    touch "$2/manifest"
}

# each expected line must equal (after trimming) an output line, in order;
# "..." matches any text
check_output() { # expected actual
    awk '
    function trim(s) { sub(/^[ \t]+/, "", s); sub(/[ \t]+$/, "", s); return s }
    function matches(pat, s,    k, np, p, pos, i) {
        np = split(pat, p, /\.\.\./)
        if (np == 1) return s == pat
        if (substr(s, 1, length(p[1])) != p[1]) return 0
        s = substr(s, length(p[1]) + 1)
        for (k = 2; k < np; k++) {
            if (p[k] == "") continue
            i = index(s, p[k]); if (!i) return 0
            s = substr(s, i + length(p[k]))
        }
        if (p[np] == "") return 1
        return length(s) >= length(p[np]) && substr(s, length(s) - length(p[np]) + 1) == p[np]
    }
    NR == FNR { l = trim($0); if (l != "") want[++nw] = l; next }
    { got[++ng] = trim($0) }
    END {
        j = 1
        for (i = 1; i <= nw; i++) {
            while (j <= ng && !matches(want[i], got[j])) j++
            if (j > ng) { print "  expected (in order), not printed: " want[i]; exit 1 }
            j++
        }
    }' "$1" "$2"
}

# run a command in the background, printing a progress line every 20 s
with_ticker() { # label cmd...
    local label=$1; shift
    "$@" &
    local pid=$! s=0
    while kill -0 "$pid" 2> /dev/null; do
        sleep 0.1; s=$((s + 1))
        if [ $((s % 200)) -eq 0 ]; then echo "doctest: $label still running ($((s / 10)) s)" >&3; fi
    done
    wait "$pid"
}

# the C snippets: definitions (typedef, #include, functions at column 0) to
# file scope, everything else into main
split_c() { # snippet defs body
    awk -v defs="$2" -v body="$3" '
    BEGIN { indef = 0; printf "" > defs; printf "" > body }
    indef { print >> defs; if ($0 ~ /^}/) indef = 0; next }
    /^#include/ || /^typedef .*;[ \t]*(\/\*.*)?$/ { print >> defs; next }
    /^(static |typedef )/ && /\(/ && $0 !~ /;[ \t]*(\/\*.*\*\/)?[ \t]*$/ {
        print >> defs; if ($0 !~ /}[ \t]*(\/\*.*\*\/)?[ \t]*$/) indef = 1; next }
    { print >> body }' "$1"
}

LIBS_CORE=$(pkg-config --libs gsl ccd 2> /dev/null)

for md in "$@"; do
    name=$(echo "$md" | tr '/.' '__')
    bdir=$WORK/blocks/$name
    extract "$md" "$bdir"
    scratch=$WORK/$name
    mkdir -p "$scratch/figures/data"
    for e in "$ROOT"/*; do
        b=$(basename "$e")
        case $b in build*|figures) continue ;; esac
        ln -s "$e" "$scratch/$b"
    done
    ln -s "$ROOT/$BUILD" "$scratch/build"
    last_out="" skip_output=0
    while IFS='|' read -r idx line kind opts; do
        blk=$bdir/$idx
        where="$md:$line"
        if [ "$LONG" = 1 ]; then case $kind in run|output) ;; *) continue ;; esac; fi
        case $kind in
        bad)
            nfail=$((nfail + 1)); failures+=("$where: a shell block without a doctest marker (tests/doctest/run.sh)")
            echo "doctest $where: FAIL (no marker)" ;;
        unknown:*)
            nfail=$((nfail + 1)); failures+=("$where: unknown marker '${kind#unknown:}'")
            echo "doctest $where: FAIL (unknown marker)" ;;
        skip)
            nskip=$((nskip + 1)); skipped+=("$where: $opts") ;;
        run)
            timeout=$DEFAULT_TIMEOUT expect_exit=0 long=0
            for o in $opts; do
                case $o in timeout=*) timeout=${o#timeout=} ;; exit=*) expect_exit=${o#exit=} ;; long) long=1 ;; esac
            done
            if [ "$long" != "$LONG" ]; then
                last_out="" skip_output=1
                if [ "$long" = 1 ]; then nskip=$((nskip + 1)); skipped+=("$where: long, run by make test-long"); fi
                continue
            fi
            nrun=$((nrun + 1))
            last_out=$blk.log skip_output=0
            t0=$(date +%s)
            with_ticker "$where" timeout --kill-after=5 "$timeout" \
                bash -c "cd '$scratch' && set -e -o pipefail && source '$blk'" > "$last_out" 2>&1
            rc=$?
            dt=$(( $(date +%s) - t0 ))
            if [ "$rc" -eq 124 ] || [ "$rc" -eq 137 ]; then
                nfail=$((nfail + 1)); failures+=("$where: timed out after $timeout s")
                echo "doctest $where: FAIL (timeout $timeout s)"; tail -5 "$last_out" | sed 's/^/  | /'
                last_out="" skip_output=1
            elif [ "$rc" -ne "$expect_exit" ]; then
                nfail=$((nfail + 1)); failures+=("$where: exit $rc, expected $expect_exit")
                echo "doctest $where: FAIL (exit $rc, expected $expect_exit, $dt s)"; tail -8 "$last_out" | sed 's/^/  | /'
                last_out="" skip_output=1
            else
                nok=$((nok + 1)); echo "doctest $where: ok ($dt s)"
            fi ;;
        output)
            if [ "$skip_output" = 1 ]; then
                continue
            elif [ -z "$last_out" ]; then
                nfail=$((nfail + 1)); failures+=("$where: an output block without a passing runnable block above it")
                echo "doctest $where: FAIL (output of nothing)"
            elif msg=$(check_output "$blk" "$last_out"); then
                echo "doctest $where: output ok"
            else
                nok=$((nok - 1)); nfail=$((nfail + 1)); failures+=("$where: output differs")
                echo "doctest $where: FAIL (output)"; echo "$msg"; sed 's/^/  | /' "$last_out" | tail -15
            fi ;;
        c)
            nc=$((nc + 1))
            harness=tests/doctest/$opts.c
            split_c "$blk" "$blk.defs.h" "$blk.body.h"
            if [ ! -f "$harness" ]; then
                nfail=$((nfail + 1)); failures+=("$where: no harness $harness")
                echo "doctest $where: FAIL (no $harness)"; continue
            fi
            hasmain=""
            if grep -q '^int main' "$blk"; then hasmain=-DSNIP_HAS_MAIN; fi
            if ! "$CC" -std=c99 -Wall -Wextra -Wpedantic -Werror -O1 -ffp-contract=off -Iinclude \
                    -DSNIP_DEFS="\"$blk.defs.h\"" -DSNIP_BODY="\"$blk.body.h\"" $hasmain -Wno-unused-variable -Wno-unused-but-set-variable \
                    -o "$blk.exe" "$harness" "$BUILD/libcapdyn.a" $LIBS_CORE -lm > "$blk.log" 2>&1; then
                nfail=$((nfail + 1)); failures+=("$where: does not compile in $harness")
                echo "doctest $where: FAIL (compile, $harness)"; head -20 "$blk.log" | sed 's/^/  | /'
            elif ! (cd "$scratch" && timeout "$DEFAULT_TIMEOUT" "$blk.exe") > "$blk.run.log" 2>&1; then
                nfail=$((nfail + 1)); failures+=("$where: the program of $harness fails")
                echo "doctest $where: FAIL (run, $harness)"; tail -8 "$blk.run.log" | sed 's/^/  | /'
            else
                echo "doctest $where: C ok ($harness)"
            fi ;;
        esac
    done < "$bdir/manifest"
done

echo "doctest: blocks not run here ($nskip):"
for s in ${skipped[@]+"${skipped[@]}"}; do echo "  $s"; done
echo "doctest: $nok of $nrun shell blocks pass, $nc C snippets built and run, $nfail failures, $(( $(date +%s) - t_start )) s"
if [ "$nfail" -gt 0 ]; then
    for f in "${failures[@]}"; do echo "  FAIL $f"; done
    exit 1
fi
