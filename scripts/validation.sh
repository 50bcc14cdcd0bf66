#!/usr/bin/env bash
# Validation runs on the 2D standard wet system (docs/model.md 1: N = 1200, 400 d x 9 d, sigma_p 0.06,
# thin thread, hot start T_g/E_cb = 20), one `wetgran simulate --json` per point, then the
# classification table of docs/validation.md. Opt-in and long (about 1-3 min per point on one
# core of the development machine); see docs/validation.md for the sets.
#
#   scripts/validation.sh point NAME GAMMA ESTAR [EPS] [DURATION] [TRANSIENT] [SPP] [N] [LX] [SEED]
#       one point: writes OUT/NAME.toml and OUT/NAME.json (OUT = $VALIDATION_OUT or ./validation)
#   scripts/validation.sh set calibration|sampling|line-eps1|line-eps096|invariance
#       the sets of docs/validation.md
#   scripts/validation.sh table FILE.json...
#       the markdown table (classified with the current rules and default thresholds)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
out="${VALIDATION_OUT:-validation}"
mkdir -p "$out"
bin="$root/target/release/wetgran"
table="$root/target/release/examples/classify_result"
build() { (cd "$root" && cargo build --release --bin wetgran --example classify_result >&2); }

point() {
    local name=$1 g=$2 e=$3 eps=${4:-1.0} dur=${5:-300} tt=${6:-100} spp=${7:-20} n=${8:-1200} lx=${9:-400.0} seed=${10:-1}
    # Transient given in time units; the scene counts it in driving periods T = 2 pi v_w / (Gamma g),
    # v_w = sqrt(2 E* E_cb / m) (docs/model.md 4.1).
    local tp
    tp=$(awk -v g="$g" -v e="$e" -v tt="$tt" 'BEGIN { vw = sqrt(2 * e * 0.2844); T = 2 * 3.141592653589793 * vw / g; printf "%.10g", tt / T }')
    cat > "$out/$name.toml" <<EOT
dimension = 2
gravity = 1.0
[box]
size = [$lx, 9.0]
boundary = ["periodic", "wall"]
[particles]
count = $n
polydispersity = 0.06
[contact]
restitution = $eps
wall_restitution = 1.0
[capillary]
model = "thin_thread"
s_crit = 0.0711
e_cb = 0.2844
[drive]
kind = "sine"
gamma = $g
e_star = $e
[engine]
min_rebound_speed = 0.03
[initial]
temperature_over_ecb = 20.0
seed = $seed
[run]
duration = $dur
sample_interval = 10.0
[observe]
transient_periods = $tp
samples_per_period = $spp
# f_lc is reported by the sampling set (docs/validation.md) and enters "halves agree".
location_changes = true
EOT
    echo "$name: Gamma = $g, E* = $e, eps = $eps, $dur time units (transient $tt), $spp samples/period, N = $n, L_x = $lx, seed $seed" >&2
    "$bin" simulate --json "$out/$name.toml" > "$out/$name.json"
}

case "${1:-}" in
point)
    shift; build; point "$@" ;;
set)
    build
    case "${2:-}" in
    calibration)
        for g in 0.6 0.9 1.1 1.3 1.6 2.5; do point "S_0.9_g${g}_e0.3" "$g" 0.3 0.9; done
        for e in 0.3 1.0; do for g in 0.6 1.1 1.6; do point "S_0.96_g${g}_e${e}" "$g" "$e" 0.96; done; done
        point D_g0.8_e0.3 0.8 0.3; point C_g2_e0.5 2 0.5
        point A_g30_e1.2 30 1.2; point F_g20_e0.3 20 0.3 ;;
    sampling)
        for s in 10 40; do point "D_g0.8_e0.3_s$s" 0.8 0.3 1.0 300 100 "$s"; point "C_g2_e0.5_s$s" 2 0.5 1.0 300 100 "$s"; point "A_g30_e1.2_s$s" 30 1.2 1.0 300 100 "$s"; done ;;
    line-eps1)
        for e in 0.5 0.7 0.9 1.1 1.3 1.6 1.9 2.2 2.6 3.0; do point "L_1.0_g30_e$e" 30 "$e" 1.0; done ;;
    line-eps096)
        for e in 0.5 0.7 0.9 1.1 1.3 1.6 1.9 2.2 2.6 3.0; do point "L_0.96_g30_e$e" 30 "$e" 0.96; done ;;
    invariance)
        for e in 0.7 1.1 1.6; do
            point "I_long_e$e" 30 "$e" 1.0 600 100
            point "I_seed2_e$e" 30 "$e" 1.0 300 100 20 1200 400.0 2
            point "I_wide_e$e" 30 "$e" 1.0 300 100 20 2400 800.0
        done ;;
    *) echo "usage: $0 set calibration|sampling|line-eps1|line-eps096|invariance" >&2; exit 2 ;;
    esac ;;
table)
    shift; build; "$table" --table "$@" ;;
*)
    sed -n '2,13p' "$0" >&2; exit 2 ;;
esac
