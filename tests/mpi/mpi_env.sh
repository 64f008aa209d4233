# Sourced by tests/mpi/*.sh after `set -u`: finds mpirun (exit 77, skipped, when it is missing),
# sets OpenMPI up for one machine and defines mpi (`mpirun -np 2 ffcube …`) and fail. Needs
# $ffcube set.
mpirun=$(command -v mpirun) || { echo "mpirun not found: skipped"; exit 77; }
# CI runs as root; OpenMPI refuses that unless told (both variables).
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
# One machine with few cores, no network: the shared-memory and self transports only.
export OMPI_MCA_btl=self,vader OMPI_MCA_rmaps_base_oversubscribe=1
mpi() { "$mpirun" --oversubscribe -np 2 "$ffcube" "$@"; }
fail() { echo "FAIL: $*"; exit 1; }
