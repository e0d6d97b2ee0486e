# Starts of the friction runs over q x omega x zeta (README, "False singular
# points"): bash reference/initialization_sweep.sh ANM TAG prints, per run,
# case, q, omega, zeta, stop reason, stop time and summary.json `init`.
# Writes its scenes and runs under /tmp/st (created).
mkdir -p /tmp/st
B=$1; tag=$2
for c in friction-plane friction-roller; do for q in 0.1 0.3 0.5 0.7; do for w in 1e-1 1e-2 1e-4 1e-6; do for z in 1e-2 1e-4; do
sed -e "s/^omega = .*/omega = $w/" -e "s/^zeta = [0-9.e-]*/zeta = $z/" -e "s/^q = .*/q = $q/" $(dirname "$0")/../scenes/$c.toml > /tmp/st/qs.toml
r=$($B run /tmp/st/qs.toml -o /tmp/st/qs-$tag --quiet 2>&1 >/dev/null; python3 -c "import json;d=json.load(open('/tmp/st/qs-$tag/summary.json'));print(d['stop']['reason'], round(d['stop']['t'],4), d.get('init',''))" 2>/dev/null)
echo "$c $q $w $z $r"
done; done; done; done
