"""CHOLMOD's structures as ctypes declares them: cholmod_common, cholmod_factor, cholmod_sparse and cholmod_dense,
field by field in the order of ``cholmod_core.h``.

The header is that of the CHOLMOD cvxopt's wheels carry, 3.0.6 (SuiteSparse 4.4.6,
``CHOLMOD/Include/cholmod_core.h``). ctypes lays fields out as the C compiler does, each at its natural
alignment, so every offset below is the header's on the platform at hand; tests/sparse/test_cholmod_structs.py
holds them on 64-bit platforms to the offsets the compiler gives for that header and reads them back from
the library. cholmod_factor, cholmod_sparse and cholmod_dense are declared whole; they kept their fields' order
from CHOLMOD 1 to 5. cholmod_common is declared up to its statistics (``blas_ok``) and then kept as room: its
remaining fields (SuiteSparseQR's and the GPU's) are never read here, and the room lets a CHOLMOD whose common
is larger (version 5's is under 8 kB, 3.0.6's 2,664 bytes) fill it without writing past its end before
:func:`mace_fmu.sparse.cholmod.symbolic_factor` checks the defaults it reads.
"""

from __future__ import annotations

import ctypes

#: The bytes set aside for a cholmod_common, its declared fields and the room after them.
COMMON_BYTES = 1 << 16
#: CHOLMOD_MAXMETHODS: cholmod_common holds one more ordering method than this.
MAX_METHODS = 9

#: itype: every integer array a 64-bit SuiteSparse_long (the cholmod_l_* routines)
CHOLMOD_LONG = 2
#: xtype: real values
CHOLMOD_REAL = 1
#: dtype: double precision
CHOLMOD_DOUBLE = 0
#: supernodal: a supernodal or simplicial analysis as the matrix's flop count per entry says
CHOLMOD_AUTO = 1
#: supernodal: always a supernodal analysis
CHOLMOD_SUPERNODAL = 2
#: cholmod_solve's system A x = b
CHOLMOD_A = 0
#: Common->status after a factorisation that met a non-positive pivot (a warning: the factor holds its columns
#: before Factor->minor)
CHOLMOD_NOT_POSDEF = 1


class CholmodMethod(ctypes.Structure):
    """One ordering method of cholmod_common (``struct cholmod_method_struct``): its statistics and parameters."""

    _fields_ = [("lnz", ctypes.c_double), ("fl", ctypes.c_double), ("prune_dense", ctypes.c_double),
                ("prune_dense2", ctypes.c_double), ("nd_oksep", ctypes.c_double), ("other_1", ctypes.c_double * 4),
                ("nd_small", ctypes.c_size_t), ("other_2", ctypes.c_size_t * 4), ("aggressive", ctypes.c_int),
                ("order_for_lu", ctypes.c_int), ("nd_compress", ctypes.c_int), ("nd_camd", ctypes.c_int),
                ("nd_components", ctypes.c_int), ("ordering", ctypes.c_int), ("other_3", ctypes.c_size_t * 4)]


class _CommonFields(ctypes.Structure):
    """cholmod_common from its first field to its statistics."""

    _fields_ = [
        # parameters of the symbolic and numeric factorisation
        ("dbound", ctypes.c_double), ("grow0", ctypes.c_double), ("grow1", ctypes.c_double),
        ("grow2", ctypes.c_size_t), ("maxrank", ctypes.c_size_t), ("supernodal_switch", ctypes.c_double),
        ("supernodal", ctypes.c_int), ("final_asis", ctypes.c_int), ("final_super", ctypes.c_int),
        ("final_ll", ctypes.c_int), ("final_pack", ctypes.c_int), ("final_monotonic", ctypes.c_int),
        ("final_resymbol", ctypes.c_int), ("zrelax", ctypes.c_double * 3), ("nrelax", ctypes.c_size_t * 3),
        ("prefer_zomplex", ctypes.c_int), ("prefer_upper", ctypes.c_int), ("quick_return_if_not_posdef", ctypes.c_int),
        ("prefer_binary", ctypes.c_int),
        # printing and errors
        ("print", ctypes.c_int), ("precise", ctypes.c_int), ("try_catch", ctypes.c_int),
        ("error_handler", ctypes.c_void_p),
        # orderings
        ("nmethods", ctypes.c_int), ("current", ctypes.c_int), ("selected", ctypes.c_int),
        ("method", CholmodMethod * (MAX_METHODS + 1)), ("postorder", ctypes.c_int), ("default_nesdis", ctypes.c_int),
        ("metis_memory", ctypes.c_double), ("metis_dswitch", ctypes.c_double), ("metis_nswitch", ctypes.c_size_t),
        # workspace
        ("nrow", ctypes.c_size_t), ("mark", ctypes.c_int64), ("iworksize", ctypes.c_size_t),
        ("xworksize", ctypes.c_size_t), ("Flag", ctypes.c_void_p), ("Head", ctypes.c_void_p),
        ("Xwork", ctypes.c_void_p), ("Iwork", ctypes.c_void_p), ("itype", ctypes.c_int), ("dtype", ctypes.c_int),
        ("no_workspace_reallocate", ctypes.c_int),
        # statistics
        ("status", ctypes.c_int), ("fl", ctypes.c_double), ("lnz", ctypes.c_double), ("anz", ctypes.c_double),
        ("modfl", ctypes.c_double), ("malloc_count", ctypes.c_size_t), ("memory_usage", ctypes.c_size_t),
        ("memory_inuse", ctypes.c_size_t), ("nrealloc_col", ctypes.c_double), ("nrealloc_factor", ctypes.c_double),
        ("ndbounds_hit", ctypes.c_double), ("rowfacfl", ctypes.c_double), ("aatfl", ctypes.c_double),
        ("called_nd", ctypes.c_int), ("blas_ok", ctypes.c_int)]


class CholmodCommon(_CommonFields):
    """cholmod_common, CHOLMOD's parameters, statistics and workspace: the fields up to ``blas_ok``, then room to
    :data:`COMMON_BYTES` in all for the rest (see the module's text). ``cholmod_l_start`` fills it."""

    _fields_ = [("room", ctypes.c_char * (COMMON_BYTES - ctypes.sizeof(_CommonFields)))]


class CholmodFactor(ctypes.Structure):
    """cholmod_factor, a symbolic or numeric L L^T or L D L^T factor: read where CHOLMOD or cvxopt made it
    (``CholmodFactor.from_address``), never allocated here."""

    _fields_ = [
        # simplicial and supernodal
        ("n", ctypes.c_size_t), ("minor", ctypes.c_size_t), ("Perm", ctypes.c_void_p), ("ColCount", ctypes.c_void_p),
        ("IPerm", ctypes.c_void_p),
        # simplicial
        ("nzmax", ctypes.c_size_t), ("p", ctypes.c_void_p), ("i", ctypes.c_void_p), ("x", ctypes.c_void_p),
        ("z", ctypes.c_void_p), ("nz", ctypes.c_void_p), ("next", ctypes.c_void_p), ("prev", ctypes.c_void_p),
        # supernodal (x above holds the supernodes' values too)
        ("nsuper", ctypes.c_size_t), ("ssize", ctypes.c_size_t), ("xsize", ctypes.c_size_t),
        ("maxcsize", ctypes.c_size_t), ("maxesize", ctypes.c_size_t), ("super", ctypes.c_void_p),
        ("pi", ctypes.c_void_p), ("px", ctypes.c_void_p), ("s", ctypes.c_void_p),
        # the factor's kind
        ("ordering", ctypes.c_int), ("is_ll", ctypes.c_int), ("is_super", ctypes.c_int),
        ("is_monotonic", ctypes.c_int), ("itype", ctypes.c_int), ("xtype", ctypes.c_int), ("dtype", ctypes.c_int),
        ("useGPU", ctypes.c_int)]


class CholmodSparse(ctypes.Structure):
    """cholmod_sparse, a matrix in compressed columns (here: a symmetric one's lower triangle, on numpy's arrays)."""

    _fields_ = [("nrow", ctypes.c_size_t), ("ncol", ctypes.c_size_t), ("nzmax", ctypes.c_size_t),
                ("p", ctypes.c_void_p), ("i", ctypes.c_void_p), ("nz", ctypes.c_void_p), ("x", ctypes.c_void_p),
                ("z", ctypes.c_void_p), ("stype", ctypes.c_int), ("itype", ctypes.c_int), ("xtype", ctypes.c_int),
                ("dtype", ctypes.c_int), ("sorted", ctypes.c_int), ("packed", ctypes.c_int)]


class CholmodDense(ctypes.Structure):
    """cholmod_dense, a column-major matrix of leading dimension ``d``."""

    _fields_ = [("nrow", ctypes.c_size_t), ("ncol", ctypes.c_size_t), ("nzmax", ctypes.c_size_t),
                ("d", ctypes.c_size_t), ("x", ctypes.c_void_p), ("z", ctypes.c_void_p),
                ("xtype", ctypes.c_int), ("dtype", ctypes.c_int)]
