# Sourced by time-quality.sh and quarter-seeds.sh: one `fsot optimize` run timed
# as a whole process, its figures appended to a table.
#
#   timed_run TSV STEM ROW args...
#
# Runs `args... --out STEM.exr` under /usr/bin/time into STEM.log, then appends
# to TSV (and prints) ROW (tab-separated leading columns), the process seconds,
# the iterations, the objective x white noise and the seconds past the budget
# ("-" without one).
timed_run() {
  local tsv=$1 stem=$2 row=$3; shift 3
  /usr/bin/time -f 'process %e s' "$@" --out "$stem.exr" >"$stem.log" 2>&1
  local secs its ratio past
  secs=$(sed -n 's/^process \([0-9.]*\) s$/\1/p' "$stem.log")
  its=$(sed -n 's/.*, \([0-9]*\) iterations in .*/\1/p' "$stem.log")
  ratio=$(sed -n 's/.*(\([0-9.]*\) x white noise).*/\1/p' "$stem.log")
  past=$(sed -n 's/.*s after \(it\|the process\) started (\([-+0-9.]*\) s).*/\2/p' "$stem.log")
  printf '%s\t%s\t%s\t%s\t%s\n' "$row" "$secs" "$its" "$ratio" "${past:--}" | tee -a "$tsv"
}
