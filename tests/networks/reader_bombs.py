"""Writes the torch.save reader bombs of issue 55 item 5 into the folder argv[1] (standard
library only; tests/networks/torch_save_limits_test.cpp and tests/app's ReaderBombs use them;
with --seeds, small files of the same shapes: fuzz/corpus/torch_save/bomb_*).

Each file is small and names, in a comment below, what it declares and what regbench must do:
refuse it naming the file before it allocates what it declares, or read it in well under a
second. Zip archives are written by hand (zip_archive), so the sizes they declare can differ
from what they hold, as a hostile file's do.
"""
import array
import struct
import sys
import zlib
from pathlib import Path

FLOAT = b"ctorch\nFloatStorage\n"
REBUILD = b"ctorch._utils\n_rebuild_tensor_v2\n"
ORDERED_DICT = b"ccollections\nOrderedDict\n"


def s(text):
    """SHORT_BINUNICODE."""
    b = text.encode()
    return b"\x8c" + bytes([len(b)]) + b


def i(value):
    """BININT (LONG1 for values beyond 32 bits)."""
    if 0 <= value < 2**31:
        return b"J" + struct.pack("<i", value)
    return b"\x8a\x08" + struct.pack("<q", value)


def tensor(key, numel, size):
    """_rebuild_tensor_v2(storage `key` of `numel` floats, 0, (size,), (1,), False, {})."""
    pid = b"(" + s("storage") + FLOAT + s(key) + s("cpu") + i(numel) + b"tQ"
    args = b"(" + pid + i(0) + b"(" + i(size) + b"t(" + i(1) + b"t\x89" + ORDERED_DICT
    return REBUILD + args + b")Rt" + b"R"


def state_dict(tensors):
    """A pickle of {name: tensor} (protocol 2) from (name, storage key, numel, size)."""
    body = b"".join(s(name) + tensor(key, numel, size) for name, key, numel, size in tensors)
    return b"\x80\x02}(" + body + b"u."


def zip_archive(records):
    """A zip of (name, method, payload, declared uncompressed size, crc) records under
    archive/, with a zip64 extra field where a declared size needs one."""
    out, central = b"", b""
    for name, method, payload, declared, crc in records:
        n = ("archive/" + name).encode()
        big = declared >= 0xFFFFFFFF
        extra = struct.pack("<HHQQ", 1, 16, declared, len(payload)) if big else b""
        usize, csize = (0xFFFFFFFF, 0xFFFFFFFF) if big else (declared, len(payload))
        offset = len(out)
        out += struct.pack("<IHHHHHIIIHH", 0x04034B50, 45, 0, method, 0, 0, crc, csize, usize,
                           len(n), len(extra)) + n + extra + payload
        central += struct.pack("<IHHHHHHIIIHHHHHII", 0x02014B50, 45, 45, 0, method, 0, 0, crc,
                               csize, usize, len(n), len(extra), 0, 0, 0, 0, offset) + n + extra
    eocd = struct.pack("<IHHHHIIH", 0x06054B50, 0, 0, len(records), len(records), len(central),
                       len(out), 0)
    return out + central + eocd


def stored(name, payload):
    return (name, 0, payload, len(payload), zlib.crc32(payload))


def deflated_zeros(mib):
    """A raw deflate stream of `mib` MiB of zeros, fast: after a full flush deflate starts
    afresh, so every flushed MiB of zeros compresses to the same bytes (about 1 KB)."""
    c = zlib.compressobj(9, zlib.DEFLATED, -15)
    first = c.compress(bytes(1 << 20)) + c.flush(zlib.Z_FULL_FLUSH)
    block = c.compress(bytes(1 << 20)) + c.flush(zlib.Z_FULL_FLUSH)
    return first + block * (mib - 1) + c.flush()


def crc_of_zeros(mib):
    crc, zeros = 0, bytes(1 << 20)
    for _ in range(mib):
        crc = zlib.crc32(zeros, crc)
    return crc


def main(folder, small=False):
    """The bombs; `small`: the same shapes with few repetitions (the fuzz seeds)."""
    folder = Path(folder)
    many = 4 if small else 64
    folder.mkdir(parents=True, exist_ok=True)
    version = stored("version", b"3\n")

    # 64 storages of 512 MiB (134217728 floats) each, 32 GiB in all, in a 9 KB zip whose
    # records hold 4 bytes each. Refused: a storage's declared bytes differ from its record's.
    big = [("w%d" % k, str(k), 1 << 27, 1 << 27) for k in range(many)]
    records = [stored("data.pkl", state_dict(big))]
    records += [stored("data/%d" % k, bytes(4)) for k in range(many)]
    (folder / "storages_64x512mib.pth").write_bytes(zip_archive(records + [version]))

    # The same pickle in the legacy stream, which ends after the first storage's count.
    magic = b"\x80\x02\x8a\x0a" + bytes.fromhex("6cfc9c46f9206aa85019") + b"."
    legacy = magic + b"\x80\x02M\xe9\x03." + b"\x80\x02}(" + s("little_endian") + b"\x88u."
    legacy += state_dict(big) + b"\x80\x02](" + b"".join(s(str(k)) for k in range(many)) + b"e."
    legacy += struct.pack("<q", 1 << 27)
    (folder / "storages_64x512mib_legacy.pth").write_bytes(legacy)

    # 389 KB of deflated bytes that declare 5 GiB (zip64): more than deflate's 1032:1 can give.
    payload = zlib.compress(bytes(range(256)) * 2000, 1)[2:-4]
    payload = (payload * 400)[: (4 if small else 389) * 1024]
    records = [stored("data.pkl", state_dict([("w", "0", 5 << 28, 5 << 28)]))]
    records += [("data/0", 8, payload, 5 << 30, 0), version]
    (folder / "declares_5gib.pth").write_bytes(zip_archive(records))

    # Three storages of 800 MiB of deflated zeros (2.4 GiB; each within 1032:1), a 2.4 MB
    # file: more than the reader's budget in all. Their CRCs are not computed (0): the reader
    # must refuse the file from the declared sizes, before it inflates a byte.
    mib = 1 if small else 800
    stream = deflated_zeros(mib)
    n = mib << 18  # floats
    records = [stored("data.pkl", state_dict([("w%d" % k, str(k), n, n) for k in range(3)]))]
    records += [("data/%d" % k, 8, stream, mib << 20, 0) for k in range(3)] + [version]
    (folder / "deflated_2400mib.pth").write_bytes(zip_archive(records))

    # A record that declares 24 bytes (its storage's 6 floats) whose deflate stream goes on
    # for 64 MiB: inflating must stop at the declared size.
    records = [stored("data.pkl", state_dict([("w", "0", 6, 6)]))]
    stream = deflated_zeros(1 if small else 64)
    records += [("data/0", 8, stream, 24, zlib.crc32(bytes(24))), version]
    (folder / "inflates_past_declared.pth").write_bytes(zip_archive(records))

    # 20,000 tensors sharing one storage of the floats 0 .. 99,999 (400 KB), tensor tK a
    # one-element view at offset K (so it holds K); the storage, the function and OrderedDict
    # kept in the memo (1, 2, 3). Must be read, quickly: each storage is read once.
    tensors, floats = (200, 1000) if small else (20000, 100000)
    pid = b"(" + s("storage") + FLOAT + s("0") + s("cpu") + i(floats) + b"tQ"
    pickle = bytearray(b"\x80\x02}(")
    for k in range(tensors):
        first = k == 0
        fn = REBUILD + b"q\x02" if first else b"h\x02"
        storage = pid + b"q\x01" if first else b"h\x01"
        od = ORDERED_DICT + b"q\x03" if first else b"h\x03"
        args = b"(" + storage + i(k) + b"(" + i(1) + b"t(" + i(1) + b"t\x89" + od
        pickle += s("t%d" % k) + fn + args + b")Rt" + b"R"
    pickle += b"u."
    assert sys.byteorder == "little"
    storage = array.array("f", range(floats)).tobytes()
    records = [stored("data.pkl", bytes(pickle)), stored("data/0", storage), version]
    (folder / "shared_20k.pth").write_bytes(zip_archive(records))

    # A million REDUCE calls of _rebuild_tensor_v2 on one argument tuple (kept in the memo)
    # with 1,000 arguments beyond its 6, each result appended to a list: 12 MB.
    args = b"(" + pid + i(0) + b"(" + i(1) + b"t(" + i(1) + b"t\x89" + ORDERED_DICT + b")R"
    args += b"K\x00" * 1000 + b"t"
    # memo 0: the list, 1: the function, 2: the arguments; the first call from the stack.
    pickle = bytearray(b"\x80\x02]r\x00\x00\x00\x00" + REBUILD + b"r\x01\x00\x00\x00")
    pickle += args + b"r\x02\x00\x00\x00Ra"
    pickle += (b"j\x01\x00\x00\x00j\x02\x00\x00\x00Ra") * (999 if small else 999999) + b"."
    records = [stored("data.pkl", bytes(pickle)), stored("data/0", bytes(4 * floats)), version]
    (folder / "reduce_1m_wide.pth").write_bytes(zip_archive(records))

    # The same million calls with the regular 6 arguments.
    args = b"(" + pid + i(0) + b"(" + i(1) + b"t(" + i(1) + b"t\x89" + ORDERED_DICT + b")Rt"
    pickle = bytearray(b"\x80\x02]r\x00\x00\x00\x00" + REBUILD + b"r\x01\x00\x00\x00")
    pickle += args + b"r\x02\x00\x00\x00Ra"
    pickle += (b"j\x01\x00\x00\x00j\x02\x00\x00\x00Ra") * (999 if small else 999999) + b"."
    records = [stored("data.pkl", bytes(pickle)), stored("data/0", bytes(4 * floats)), version]
    (folder / "reduce_1m.pth").write_bytes(zip_archive(records))

    # One float viewed with stride 0 as 2^30 of them (4 GiB once copied out, beyond the
    # budget) and as 2^29 (2 GiB, within it).
    for log2, gib in ((30, 4), (29, 2)):
        pid = b"(" + s("storage") + FLOAT + s("0") + s("cpu") + i(1) + b"tQ"
        args = b"(" + pid + i(0) + b"(" + i(1 << log2) + b"t(" + i(0) + b"t\x89" + ORDERED_DICT
        pickle = b"\x80\x02}(" + s("w") + REBUILD + args + b")Rt" + b"Ru."
        records = [stored("data.pkl", pickle), stored("data/0", bytes(4)), version]
        (folder / ("stride0_%dgib.pth" % gib)).write_bytes(zip_archive(records))


if __name__ == "__main__":
    main(sys.argv[1], "--seeds" in sys.argv[2:])
