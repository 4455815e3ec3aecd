#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# This file is part of Normal_orientation.
#
# global_quality.sh BUILD_DIR [--sizes "4000 30000 200000 1000000"] [--noise "0 0.002 0.005"]
#                   [--meshes DIR_OR_FILES] [--clouds DIR] [--stream] [--ipsr IPSR_BINARY] [--out FILE.md]
#                   [--seed S] [--timeout S] [--ipsr-timeout S] [--ipsr-max-points N] [--keep DIR]
#
# The quality table of issue 15 (item 7): wrong normals of our orientation before and after the
# global sign stage, of CGAL::mst_orient_normals and, when given, of iPSR, on clouds sampled on
# closed, outward-oriented meshes (make_cloud: PCA normals, random signs) or on pre-made clouds.
# Each output is scored by score_normals against the truth: the wrong normals over all normals
# and over the clear ones, whose line is within 60 degrees of the truth. See benchmark/README.md.
set -euo pipefail

usage() {
  cat >&2 <<'USAGE'
usage: global_quality.sh BUILD_DIR [options]
  --sizes "N1 N2 ..."     points per cloud (default "4000 30000 200000 1000000")
  --noise "F1 F2 ..."     noise, fraction of the bounding-box diagonal (default "0 0.002 0.005")
  --meshes DIR_OR_FILES   a directory of .off meshes, or a list of mesh files in one argument
                          (default /work/shared/data/meshes)
  --clouds DIR            score pre-made clouds instead: pairs DIR/NAME.xyz + DIR/NAME.gt.xyz
                          (--sizes, --noise and --meshes are then ignored)
  --stream                add the column of ours streamed (orient_normals --stream --keep-order,
                          the defaults otherwise), to compare the two drivers on the same clouds
  --ipsr IPSR_BINARY      add the iPSR column (benchmark/ipsr/build_ipsr.sh builds it)
  --out FILE.md           also write the table to FILE.md
  --seed S                make_cloud seed (default 1)
  --timeout S             limit of each run of ours and CGAL, in seconds (default 600)
  --ipsr-timeout S        limit of each iPSR run (default 300; a longer run shows "timeout")
  --ipsr-max-points N     skip iPSR on larger clouds (default 300000)
  --keep DIR              keep clouds, outputs and logs in DIR (default: a temporary directory)
"Ours, before" is orient_normals --global none when the CLI has --global, else orient_normals;
"ours, after" is orient_normals with its defaults. Markdown on stdout, progress on stderr.
Exit status: 0 when every run succeeded, 1 when a run failed or timed out, 2 on bad usage.
USAGE
  exit 2
}

[[ $# -ge 1 && "$1" != -h && "$1" != --help ]] || usage
build=$1
shift
# The command line as typed: arguments with blanks in double quotes.
command_line="global_quality.sh"
for argument in "$build" "$@"; do
  [[ "$argument" == *[[:space:]]* ]] && command_line+=" \"$argument\"" || command_line+=" $argument"
done
sizes="4000 30000 200000 1000000"
noises="0 0.002 0.005"
meshes=/work/shared/data/meshes
clouds=""
ipsr=""
out=""
seed=1
run_timeout=600
ipsr_timeout=300
ipsr_max_points=300000
keep=""
stream=0
while [[ $# -gt 0 ]]; do
  if [[ $1 == --stream ]]; then
    stream=1
    shift
    continue
  fi
  [[ $# -ge 2 ]] || { echo "global_quality.sh: $1 needs a value" >&2; usage; }
  case $1 in
    --sizes) sizes=${2//,/ } ;;
    --noise) noises=${2//,/ } ;;
    --meshes) meshes=$2 ;;
    --clouds) clouds=$2 ;;
    --ipsr) ipsr=$2 ;;
    --out) out=$2 ;;
    --seed) seed=$2 ;;
    --timeout) run_timeout=$2 ;;
    --ipsr-timeout) ipsr_timeout=$2 ;;
    --ipsr-max-points) ipsr_max_points=$2 ;;
    --keep) keep=$2 ;;
    *) echo "global_quality.sh: unknown option '$1'" >&2; usage ;;
  esac
  shift 2
done

script_dir=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
ours=$build/examples/orient_normals
make_cloud=$build/benchmark/make_cloud
cgal=$build/benchmark/cgal_mst_orient
score=$build/benchmark/score_normals
transfer=$build/benchmark/transfer_signs
for program in "$ours" "$cgal" "$score"; do
  [[ -x "$program" ]] || { echo "global_quality.sh: '$program' is missing (build it)" >&2; exit 2; }
done
[[ -n "$clouds" || -x "$make_cloud" ]] || { echo "global_quality.sh: '$make_cloud' is missing" >&2; exit 2; }
if [[ -n "$ipsr" ]]; then
  [[ -x "$ipsr" ]] || { echo "global_quality.sh: iPSR binary '$ipsr' is not executable" >&2; exit 2; }
  [[ -x "$transfer" ]] || { echo "global_quality.sh: '$transfer' is missing (build it)" >&2; exit 2; }
fi

# The two runs of ours.
help_text=$("$ours" --help 2>&1 || true) # (not piped into grep -q: SIGPIPE under pipefail)
if [[ "$help_text" == *--global* ]]; then
  before_args=(--global none)
  before_note="\`orient_normals --global none\`"
  same_program=0
else
  before_args=()
  before_note="\`orient_normals\` (this CLI has no \`--global\`: before and after are the same run, made once)"
  same_program=1
fi

if [[ -n "$keep" ]]; then
  mkdir -p "$keep"
  work=$keep
else
  work=$(mktemp -d "${TMPDIR:-/tmp}/global_quality.XXXXXX")
  trap 'rm -rf "$work"' EXIT
fi

columns=(before after)
[[ $stream -eq 0 ]] || columns+=(stream)
columns+=(cgal)
[[ -n "$ipsr" ]] && columns+=(ipsr)
declare -A title=([before]="ours, before" [after]="ours, after" [stream]="ours, --stream" [cgal]="CGAL" [ipsr]="iPSR")
# Results, keyed by "ROW,COLUMN": cell status (ok, FAILED, timeout, skipped) and counts.
declare -A status points wrong clear clear_wrong seconds
rows=()          # row keys, in order
declare -A row_label row_n row_noise
failures=0

# Prints the integer or decimal value of "name" in the one-line JSON object $2.
json_field() { sed -n "s/.*\"$1\":\([-0-9.eE+]*\).*/\1/p" <<< "$2"; }

# run_cell ROW COLUMN TIMEOUT IN GT OUT COMMAND...: runs COMMAND, times it and scores OUT.
run_cell() {
  local row=$1 column=$2 limit=$3 input=$4 truth=$5 output=$6
  shift 6
  local log=$work/$row.$column.log start end code=0 result
  rm -f "$output"
  start=$(date +%s.%N)
  timeout -k 10 "$limit" "$@" > "$log" 2>&1 < /dev/null || code=$?
  end=$(date +%s.%N)
  seconds[$row,$column]=$(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.2f", b - a }')
  if [[ $code -eq 124 || $code -eq 137 ]]; then
    status[$row,$column]=timeout
  elif [[ $code -ne 0 ]]; then
    status[$row,$column]=FAILED
    echo "  $column FAILED (exit $code); the end of $log:" >&2
    tail -3 "$log" | sed 's/^/    /' >&2
  elif ! result=$("$score" "$output" "$truth" --json 2>> "$log"); then
    status[$row,$column]=FAILED
    echo "  $column FAILED: $(tail -1 "$log")" >&2
  else
    status[$row,$column]=ok
    points[$row,$column]=$(json_field points "$result")
    wrong[$row,$column]=$(json_field wrong "$result")
    clear[$row,$column]=$(json_field clear "$result")
    clear_wrong[$row,$column]=$(json_field clear_wrong "$result")
  fi
  [[ ${status[$row,$column]} == ok ]] || failures=$((failures + 1))
  if [[ ${status[$row,$column]} == ok ]]; then
    echo "  $column: ${seconds[$row,$column]} s, ${wrong[$row,$column]} wrong," \
         "${clear_wrong[$row,$column]} of ${clear[$row,$column]} clear" >&2
  else
    echo "  $column: ${status[$row,$column]} after ${seconds[$row,$column]} s" >&2
  fi
  [[ -n "$keep" ]] || rm -f "$output"
}

# orient_row ROW PREFIX: runs every column on PREFIX.xyz, scored against PREFIX.gt.xyz.
orient_row() {
  local row=$1 prefix=$2 n
  n=$(awk 'NF >= 6 && $1 !~ /^#/' "$prefix.gt.xyz" | wc -l)
  row_n[$row]=$n
  run_cell "$row" before "$run_timeout" "$prefix.xyz" "$prefix.gt.xyz" "$work/$row.before.xyz" \
    "$ours" --quiet "${before_args[@]}" "$prefix.xyz" "$work/$row.before.xyz"
  if [[ $same_program -eq 1 ]]; then
    for field in status points wrong clear clear_wrong seconds; do
      declare -n table=$field
      [[ -z "${table[$row,before]+x}" ]] || table[$row,after]=${table[$row,before]}
      unset -n table
    done
  else
    run_cell "$row" after "$run_timeout" "$prefix.xyz" "$prefix.gt.xyz" "$work/$row.after.xyz" \
      "$ours" --quiet "$prefix.xyz" "$work/$row.after.xyz"
  fi
  if [[ $stream -eq 1 ]]; then
    run_cell "$row" stream "$run_timeout" "$prefix.xyz" "$prefix.gt.xyz" "$work/$row.stream.xyz" \
      "$ours" --quiet --stream --keep-order "$prefix.xyz" "$work/$row.stream.xyz"
  fi
  run_cell "$row" cgal "$run_timeout" "$prefix.xyz" "$prefix.gt.xyz" "$work/$row.cgal.xyz" \
    "$cgal" --quiet "$prefix.xyz" "$work/$row.cgal.xyz"
  if [[ -n "$ipsr" ]]; then
    if [[ $n -gt $ipsr_max_points ]]; then
      status[$row,ipsr]=skipped
    else
      TRANSFER_SIGNS=$transfer run_cell "$row" ipsr "$ipsr_timeout" "$prefix.xyz" "$prefix.gt.xyz" \
        "$work/$row.ipsr.xyz" bash "$script_dir/ipsr/ipsr_orient.sh" "$ipsr" "$prefix.xyz" "$work/$row.ipsr.xyz"
    fi
  fi
}

export TRANSFER_SIGNS=$transfer
if [[ -n "$clouds" ]]; then
  shopt -s nullglob
  for truth in "$clouds"/*.gt.xyz; do
    name=$(basename "$truth" .gt.xyz)
    [[ -f "$clouds/$name.xyz" ]] || { echo "global_quality.sh: no $clouds/$name.xyz for $truth" >&2; continue; }
    row=$name
    rows+=("$row")
    row_label[$row]=$name
    row_noise[$row]="-"
    echo "$name" >&2
    orient_row "$row" "$clouds/$name"
  done
  shopt -u nullglob
  [[ ${#rows[@]} -gt 0 ]] || { echo "global_quality.sh: no NAME.gt.xyz + NAME.xyz pair in '$clouds'" >&2; exit 2; }
else
  if [[ -d "$meshes" ]]; then
    mesh_files=("$meshes"/*.off)
  else
    read -r -a mesh_files <<< "$meshes"
  fi
  for n in $sizes; do
    for noise in $noises; do
      for mesh in "${mesh_files[@]}"; do
        [[ -f "$mesh" ]] || { echo "global_quality.sh: no mesh '$mesh'" >&2; exit 2; }
        name=$(basename "$mesh" .off)
        row=${name}_${n}_${noise}
        rows+=("$row")
        row_label[$row]=$name
        row_n[$row]=$n
        row_noise[$row]=$noise
        echo "$name, $n points, noise $noise" >&2
        if ! "$make_cloud" "$mesh" "$n" "$work/$row" --noise "$noise" --seed "$seed" > "$work/$row.make.log" 2>&1; then
          echo "global_quality.sh: make_cloud failed on $mesh: $(tail -1 "$work/$row.make.log")" >&2
          exit 1
        fi
        orient_row "$row" "$work/$row"
        [[ -n "$keep" ]] || rm -f "$work/$row.xyz" "$work/$row.gt.xyz"
      done
    done
  done
fi

# total_row "N NOISE" COMMON: the totals row of a size and noise (of all rows with --clouds);
# COMMON=1: only over the rows where every column succeeded.
total_row() {
  local group=$1 common=$2 column row label="**total**" line times=""
  [[ $common -eq 0 ]] || label="**total, common rows**"
  line="| $label | ${group% *} | ${group#* } |"
  for column in "${columns[@]}"; do
    local p=0 w=0 c=0 cw=0 s=0 missing=0 mark=""
    for row in "${rows[@]}"; do
      [[ -n "$clouds" || "${row_n[$row]} ${row_noise[$row]}" == "$group" ]] || continue
      if [[ $common -eq 1 ]] && ! row_complete "$row"; then
        continue
      elif [[ ${status[$row,$column]:-skipped} == ok ]]; then
        p=$((p + points[$row,$column])); w=$((w + wrong[$row,$column]))
        c=$((c + clear[$row,$column])); cw=$((cw + clear_wrong[$row,$column]))
        s=$(awk -v a="$s" -v b="${seconds[$row,$column]}" 'BEGIN { print a + b }')
      else
        missing=$((missing + 1))
      fi
    done
    [[ $missing -eq 0 ]] || mark=" ($missing missing)"
    line+=" **$(percent $w $p)** ($w)$mark | **$(percent $cw $c)** ($cw) |"
    times+=" $(awk -v a="$s" 'BEGIN { printf "%.2f", a }') |"
  done
  echo "$line$times"
}

# row_complete ROW: true when every column of ROW succeeded.
row_complete() {
  local column
  for column in "${columns[@]}"; do
    [[ ${status[$1,$column]:-skipped} == ok ]] || return 1
  done
}

# The Markdown report.
percent() { awk -v a="$1" -v b="$2" 'BEGIN { if (b > 0) printf "%.2f", 100 * a / b; else printf "-" }'; }
report() {
  local model memory header separator column row group
  model=$(lscpu 2>/dev/null | sed -n 's/^Model name: *//p' | head -1)
  memory=$(free -g 2>/dev/null | awk '/^Mem:/ { print $2 " GB" }')
  echo "## Quality: wrong normals before and after the global sign stage (issue 15)"
  echo
  echo "- date: $(date '+%Y-%m-%d %H:%M %Z')"
  echo "- machine: $(nproc) cores, ${model:-unknown CPU}, ${memory:-unknown memory}"
  echo "- command: \`$command_line\`"
  echo "- source: commit $(git -C "$script_dir" log -1 --format='%h (%cs)' 2>/dev/null || echo unknown)"
  echo "- ours, before: $before_note; ours, after: \`orient_normals\`; CGAL: \`cgal_mst_orient\` (k = 18)"
  [[ $stream -eq 0 ]] || echo "- ours, --stream: \`orient_normals --stream --keep-order\` (the streaming driver, its defaults otherwise)"
  [[ -z "$ipsr" ]] || echo "- iPSR: \`$ipsr\`, default settings, signs from the closest triangle of its mesh (\`ipsr/ipsr_orient.sh\`)"
  echo "- cells: wrong normals in % of all normals (\"all\") and of the clear normals, whose line is within 60° of the truth (\"60°\"); times: whole process, in seconds"
  echo
  header="| $([[ -n "$clouds" ]] && echo cloud || echo mesh) | n | noise |"
  separator="|---|---:|---:|"
  for column in "${columns[@]}"; do
    header+=" ${title[$column]} all | ${title[$column]} 60° |"
    separator+="---:|---:|"
  done
  for column in "${columns[@]}"; do
    header+=" ${title[$column]} s |"
    separator+="---:|"
  done
  echo "$header"
  echo "$separator"
  for row in "${rows[@]}"; do
    local line="| ${row_label[$row]} | ${row_n[$row]} | ${row_noise[$row]} |"
    for column in "${columns[@]}"; do
      if [[ ${status[$row,$column]:-skipped} == ok ]]; then
        line+=" $(percent "${wrong[$row,$column]}" "${points[$row,$column]}") | $(percent "${clear_wrong[$row,$column]}" "${clear[$row,$column]}") |"
      else
        line+=" ${status[$row,$column]:-skipped} | |"
      fi
    done
    for column in "${columns[@]}"; do
      [[ ${status[$row,$column]:-skipped} == skipped ]] && line+=" |" || line+=" ${seconds[$row,$column]} |"
    done
    echo "$line"
  done
  # Totals per size and noise; when a column has failed or skipped rows there, a second row
  # sums only the rows where every column succeeded, so that the columns compare.
  local groups=()
  declare -A seen=()
  for row in "${rows[@]}"; do
    group="${row_n[$row]} ${row_noise[$row]}"
    [[ -n "$clouds" ]] && group="all -"
    [[ -n "${seen[$group]+x}" ]] || { seen[$group]=1; groups+=("$group"); }
  done
  for group in "${groups[@]}"; do
    local first
    first=$(total_row "$group" 0)
    echo "$first"
    [[ $first != *missing* ]] || total_row "$group" 1
  done
  echo
  echo "Totals: wrong normals summed over the rows of a size and noise (in parentheses), in % of the"
  echo "summed points, and summed times; \"(k missing)\": k rows of the column failed, timed out or were"
  echo "skipped; \"total, common rows\": only the rows where every column succeeded."
}

if [[ -n "$out" ]]; then
  report | tee "$out.tmp"
  mv -f "$out.tmp" "$out"
else
  report
fi
[[ $failures -eq 0 ]]
