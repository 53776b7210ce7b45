# Sourced by scripts/test, scripts/sanitize and scripts/fuzz: the wall time of each phase of a test run.
# `phase NAME` ends the phase that began at the previous call (or when this file was sourced) and appends
# "NAME SECONDS" to $PATHCL_PHASE_LOG when that is set (scripts/test sets it and prints the table).
phase_start_us=${EPOCHREALTIME/./}
phase() {
  local now_us=${EPOCHREALTIME/./}
  if [ -n "${PATHCL_PHASE_LOG:-}" ]; then
    printf '%-28s %6d s\n' "$1" $(((now_us - phase_start_us + 500000) / 1000000)) >>"$PATHCL_PHASE_LOG"
  fi
  phase_start_us=$now_us
}
