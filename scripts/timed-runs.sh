# Sourced by the benchmark scripts: `timed_runs WORK_DIR COMMAND...` runs COMMAND up to 5 times
# (once more while a run takes under a minute) and sets `runs`, `median` (wall seconds, the
# median run) and `memory` (the largest peak resident size, KB), measured by GNU time
# (/usr/bin/time). `growth_exponent SIZE TIME PREVIOUS_SIZE PREVIOUS_TIME` prints k of
# time ∝ size^k between two measurements. `bench_header ROOT OPTIONS...` prints the line that
# says which build, day, load and options a table comes from.

timed_runs() {
    local work=$1 seconds kb times=()
    shift
    memory=0
    runs=0
    while [ "$runs" -lt 5 ]; do
        /usr/bin/time -f "%e %M" -o "$work/time" "$@"
        read -r seconds kb < "$work/time"
        times+=("$seconds")
        [ "$kb" -gt "$memory" ] && memory=$kb
        runs=$((runs + 1))
        awk -v s="$seconds" 'BEGIN { exit !(s >= 60) }' && break
    done
    median="$(printf '%s\n' "${times[@]}" | sort -g | awk '{ a[NR] = $1 } END { print a[int((NR + 1) / 2)] }')"
}

growth_exponent() {
    awk -v n="$1" -v t="$2" -v pn="$3" -v pt="$4" 'BEGIN { printf "%.2f", log(t / pt) / log(n / pn) }'
}

bench_header() {
    local root=$1
    shift
    echo "snakegrid $(git -C "$root" describe --always --dirty), $(date -u +%F), load $(cut -d' ' -f1-3 /proc/loadavg), options: ${*:-defaults}"
    echo
}
