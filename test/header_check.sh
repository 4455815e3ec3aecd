#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Every public header compiles on its own (syntax check, warnings as errors)
# and starts with an SPDX line.
# usage: header_check.sh CXX INCLUDE_DIR [extra flags...]
set -u
cxx="$1"; inc="$2"; shift 2
fails=0; passes=0
tu=$(mktemp --suffix=.cpp); trap 'rm -f "$tu"' EXIT
while IFS= read -r h; do
  rel=${h#"$inc"/}
  if ! head -1 "$h" | grep -q "SPDX-License-Identifier: GPL-3.0-or-later"; then
    echo "FAILED: $rel has no SPDX line first"; fails=$((fails + 1)); continue
  fi
  printf '#include <%s>\n#include <%s>\nint main() { return 0; }\n' "$rel" "$rel" > "$tu"
  if "$cxx" -std=c++17 -fsyntax-only -Wall -Wextra -Werror -I"$inc" "$@" "$tu" 2> "$tu.err"; then
    passes=$((passes + 1))
  else
    echo "FAILED: $rel does not compile on its own:"; head -5 "$tu.err"; fails=$((fails + 1))
  fi
  rm -f "$tu.err"
done < <(find "$inc" -name '*.h' | sort)
echo "$passes passed, $fails failed"
[ "$fails" -eq 0 ]
