#!/usr/bin/env bash
# Creates reference/peers/.venv (git-ignored) with the peers that
# factor_peers.py runs: MKL Pardiso (pypardiso, with Intel's mkl wheel) and
# MUMPS (python-mumps: its manylinux wheel bundles sequential MUMPS 5.2.1
# with the METIS, SCOTCH, PORD, AMD, AMF and QAMD orderings and its own
# OpenBLAS), and threadpoolctl (which BLAS/OpenMP pools run, how many
# threads). Wheels only, from PyPI.
# python-mumps 0.0.2, the last release with a wheel for this Python, was
# built against NumPy 1.x: numpy < 2 and a SciPy that still supports it.
# Idempotent; quiet unless something is installed.
set -euo pipefail
cd "$(dirname "$0")"
python=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
    "$python" -m venv .venv
fi
want=("numpy<2" "scipy>=1.11,<1.15" "pypardiso==0.4.7" "python-mumps==0.0.2" "threadpoolctl>=3")
if ! .venv/bin/python - <<'PY' 2>/dev/null
import numpy, scipy, pypardiso, mumps, threadpoolctl
assert numpy.__version__.startswith("1.")
PY
then
    echo "peers/setup: installing ${want[*]} into reference/peers/.venv"
    .venv/bin/python -m pip install -q --disable-pip-version-check --only-binary=:all: "${want[@]}"
fi
.venv/bin/python -c "import numpy, scipy, pypardiso, mumps; print('peers/setup: numpy', numpy.__version__, 'scipy', scipy.__version__, 'pypardiso', pypardiso.__version__ if hasattr(pypardiso, '__version__') else '?', 'python-mumps', mumps.__version__)"
