#!/usr/bin/env bash
# The figures' PDF and PNG need a font (src/report/figure.rs): DejaVu Sans, from Debian's
# fonts-dejavu-core, installed here when no TrueType or OpenType font is on the machine (as
# root, about 2 s). A machine with any such font is left as it is.
set -euo pipefail
if find /usr/share/fonts /usr/local/share/fonts -type f \( -name '*.ttf' -o -name '*.otf' \) 2>/dev/null | grep -q .; then
    exit 0
fi
apt-get update -qq
DEBIAN_FRONTEND=noninteractive apt-get install -y -qq fonts-dejavu-core
