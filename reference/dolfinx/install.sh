#!/usr/bin/env bash
# Install the Debian packages needed by reference/dolfinx/*.py (dolfinx 0.5.2 on
# Debian bookworm, gmsh Python API, h5py; slepc4py 3.18 for plate_buckling.py).
# Idempotent: re-running is harmless.
set -euo pipefail
export DEBIAN_FRONTEND=noninteractive
if /usr/bin/python3 -c "import dolfinx, gmsh, h5py, slepc4py" >/dev/null 2>&1; then
    echo "dolfinx, gmsh, h5py and slepc4py already importable by /usr/bin/python3"
    exit 0
fi
SUDO=""
if [ "$(id -u)" != "0" ]; then SUDO="sudo"; fi
$SUDO apt-get update
$SUDO apt-get install -y --no-install-recommends python3-dolfinx python3-gmsh python3-h5py python3-slepc4py
/usr/bin/python3 -c "import dolfinx, gmsh, h5py, slepc4py; print('dolfinx', dolfinx.__version__, 'gmsh', gmsh.__version__, 'h5py', h5py.__version__, 'slepc4py', slepc4py.__version__)"
