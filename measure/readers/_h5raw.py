"""A 1-D HDF5 dataset's samples read straight from the file's byte ranges (HDF5's own answer
for where they are), scanned for per-block extremes while in cache.

Unfiltered chunked or contiguous data (what :func:`measure.readers.hdf5.write` produces) is
read as ``numpy.fromfile`` reads, without HDF5's chunk-by-chunk path (about twice the time for
20 MB). The byte ranges come from HDF5 for this dataset (never stored by us) and are used only
when the file's datatype is exactly numpy's (same bytes, no conversion); anything else is read
by HDF5 (``read_direct``).

The reads go through a duplicate of HDF5's own file descriptor (:func:`vfd_dup`): the bytes
come from the very file HDF5 opened and checked (not whatever the path names a moment later),
and HDF5 can be closed before the samples are read, while its structures are still in cache.
"""

from __future__ import annotations

import builtins
import os

import numpy as np

from ..scan import BlockExtremes

#: the kernel copies from the page cache fastest when source and destination share their
#: offset within a page (about 20 % less CPU for 20 MB than at an arbitrary offset)
_PAGE = 4096

#: bytes read per system call: each piece is scanned (minimum, maximum, NaN/inf) right after
#: the kernel copied it, while it is still in cache, instead of once more from memory by the
#: record checks
_PIECE_BYTES = 1 << 21

#: numpy dtype -> HDF5 datatype h5py makes for it (a description of numpy's type, the same for
#: every file): compared with a file's datatype to know its bytes are numpy's
_NATIVE = {}


def _h5():
    import h5py

    return h5py


def native_type(dtype):
    """HDF5 datatype (``h5py.h5t.TypeID``) of numpy ``dtype``, as h5py makes it (made once)."""
    tid = _NATIVE.get(dtype)
    if tid is None:
        tid = _NATIVE[dtype] = _h5().h5t.py_create(dtype)
    return tid


def _low(ds):
    """The ``h5py.h5d.DatasetID`` of a high- or low-level dataset (whose own ``.id`` is the
    integer handle)."""
    return ds.id if isinstance(ds, _h5().Dataset) else ds


def raw_runs(ds, userblock: int | None = None, dcpl=None, shape: tuple | None = None):
    """File byte ranges holding a 1-D dataset's samples.

    Parameters
    ----------
    ds : h5py.Dataset or h5py.h5d.DatasetID
        The dataset (high- or low-level).
    userblock : int, optional
        The file's user-block size, bytes, if known (else asked here).
    dcpl : h5py.h5p.PropDCID, optional
        The dataset's creation property list, if already at hand.
    shape : tuple, optional
        The dataset's shape, if already at hand.

    Returns
    -------
    list of tuple or None
        ``[(file offset in bytes, first sample, samples)]`` with file-adjacent chunks merged, or
        None when HDF5 must do the read itself (filters, foreign byte order or bit layout,
        external or virtual storage, a user block, unallocated chunks).
    """
    h5py = _h5()
    did = _low(ds)  # h5py's low-level calls: each high-level property costs more
    dtype = did.dtype
    shape = did.shape if shape is None else shape
    if len(shape) != 1 or not dtype.isnative or dtype.kind not in "fiu":
        return None
    if did.get_type() != native_type(dtype):  # bytes not numpy's (bit offset, precision,
        return None                       # custom float): HDF5 converts
    plist = did.get_create_plist() if dcpl is None else dcpl
    layout = plist.get_layout()
    if (layout not in (h5py.h5d.CONTIGUOUS, h5py.h5d.CHUNKED)
            or plist.get_nfilters() or plist.get_external_count()):
        return None
    if userblock is None:
        userblock = h5py.h5i.get_file_id(did).get_create_plist().get_userblock()
    if userblock != 0:
        return None
    item = dtype.itemsize
    n = shape[0]
    if layout == h5py.h5d.CONTIGUOUS:
        offset = did.get_offset()
        return None if offset is None else [(int(offset), 0, n)]
    chunk = plist.get_chunk()[0]
    info = []
    did.chunk_iter(lambda si: info.append((si.chunk_offset[0], si.byte_offset, si.size,
                                             si.filter_mask)))
    if len(info) != -(-n // chunk):
        return None
    runs = []
    for first, offset, size, mask in sorted(info):
        count = min(chunk, n - first)
        if mask or size != chunk * item or offset is None:
            return None
        if runs and runs[-1][0] + runs[-1][2] * item == offset and runs[-1][1] + runs[-1][2] == first:
            runs[-1][2] += count
        else:
            runs.append([int(offset), int(first), int(count)])
    return [tuple(r) for r in runs]


def congruent_empty(n: int, dtype, file_offset: int) -> np.ndarray:
    """An uninitialised array of ``n`` items whose address is congruent to ``file_offset``
    (bytes) modulo the page size (a view into a buffer one page larger)."""
    dtype = np.dtype(dtype)
    buf = np.empty(n * dtype.itemsize + _PAGE, dtype=np.uint8)
    shift = (file_offset - buf.ctypes.data) % _PAGE
    if shift % dtype.alignment:
        shift = (shift + dtype.alignment - shift % dtype.alignment) % _PAGE
    return buf[shift:shift + n * dtype.itemsize].view(dtype)


def prepare(did, shape: tuple, userblock: int | None = None, dcpl=None):
    """The array to hold a 1-D dataset's samples and the byte ranges to fill it from.

    Parameters
    ----------
    did : h5py.h5d.DatasetID
        The dataset.
    shape : tuple
        Its shape (samples,).
    userblock : int, optional
        The file's user-block size, bytes, if known.
    dcpl : h5py.h5p.PropDCID, optional
        Its creation property list, if already at hand.

    Returns
    -------
    out : numpy.ndarray
        Uninitialised, of the dataset's shape and dtype (page-congruent to its first byte
        range when there is one).
    runs : list of tuple or None
        :func:`raw_runs`; None: ``out`` is to be filled by HDF5 (``read_direct``).
    """
    runs = None
    if shape and shape[0]:
        try:
            runs = raw_runs(did, userblock, dcpl, shape)
        except Exception:  # noqa: BLE001 - an h5py build without chunk queries: HDF5 reads
            runs = None
    if runs is None:
        return np.empty(shape, dtype=did.dtype), None
    return congruent_empty(shape[0], did.dtype, runs[0][0]), runs


def vfd_dup(fid) -> int | None:
    """A duplicate of the file descriptor HDF5 reads the open file ``fid`` (``h5py.h5f.FileID``)
    through, to read from after closing it; None where its driver has none (or this platform
    cannot read at an offset without moving the descriptor's shared position)."""
    if not hasattr(os, "preadv"):
        return None
    try:
        handle = fid.get_vfd_handle()
    except Exception:  # noqa: BLE001 - a driver without one (core, family, ...)
        return None
    if not isinstance(handle, int) or handle < 0:
        return None
    return os.dup(handle)


def positioned_reader(fd: int):
    """``pread(buffer, offset) -> bytes read`` on descriptor ``fd``: ``os.preadv`` (the
    descriptor's position untouched, so it may be shared with HDF5) or, where that is missing,
    seek and ``readinto`` (``fd`` must then be this reader's own)."""
    if hasattr(os, "preadv"):
        preadv = os.preadv
        return lambda buffer, offset: preadv(fd, (buffer,), offset)
    fh = builtins.open(fd, "rb", buffering=0, closefd=False)

    def pread(buffer, offset):
        fh.seek(offset)
        return fh.readinto(buffer)

    return pread


def read_runs(pread, runs, out: np.ndarray, block: int):
    """Fill ``out`` from the file's byte ``runs`` (:func:`raw_runs`) by ``pread(buffer, offset)``
    (:func:`positioned_reader`), folding each piece's samples into per-block extremes
    (:class:`measure.scan.BlockExtremes`) right after the kernel copied them.

    Parameters
    ----------
    pread : callable
        ``pread(buffer, offset in bytes) -> bytes read``.
    runs : list of tuple
        ``[(file offset in bytes, first sample, samples)]``.
    out : numpy.ndarray
        The array to fill (:func:`prepare`).
    block : int
        Samples per block of the extremes (:data:`measure.scan._SCAN_BLOCK`).

    Returns
    -------
    tuple of numpy.ndarray, None or False
        Per-block ``(lows, highs)`` of float data (NaN in both for a block holding NaN, inf as
        numpy's reductions give it), None for other kinds, False if the file ended early
        (truncated: HDF5 then reads and reports it).
    """
    flat = out.view(np.uint8)
    item = out.dtype.itemsize
    step = max(1, _PIECE_BYTES // item)
    extremes = BlockExtremes(out.size, out.dtype, block) if out.dtype.kind == "f" else None
    for offset, first, count in runs:
        a, stop = first, first + count
        while a < stop:
            b = min(stop, a + step)
            if pread(flat[a * item:b * item], offset + (a - first) * item) != (b - a) * item:
                return False
            if extremes is not None:
                extremes.fold(out, a, b)
            a = b
    return None if extremes is None else extremes.result()
