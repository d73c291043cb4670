"""A reader of the OpenEXR files PRT writes (scan lines of 32-bit float
channels, uncompressed, ZIPS or ZIP), with numpy and zlib alone: the tests'
check that an .exr PRT writes is what the format says, independent of the
OpenEXR library that wrote it.

  read_exr(path) -> (height, width, channels) float32 array, channels by name
"""
import struct
import zlib

import numpy as np

_LINES_PER_CHUNK = {0: 1, 2: 1, 3: 16}  # NO, ZIPS, ZIP compression


def _attributes(data, at):
    attributes = {}
    while data[at] != 0:
        name_end = data.index(b"\0", at)
        kind_end = data.index(b"\0", name_end + 1)
        name = data[at:name_end].decode()
        kind = data[name_end + 1:kind_end].decode()
        (size,) = struct.unpack_from("<i", data, kind_end + 1)
        value = data[kind_end + 5:kind_end + 5 + size]
        attributes[name] = (kind, value)
        at = kind_end + 5 + size
    return attributes, at + 1


def _channels(value):
    names, at = [], 0
    while value[at] != 0:
        end = value.index(b"\0", at)
        name = value[at:end].decode()
        pixel_type = struct.unpack_from("<i", value, end + 1)[0]
        if pixel_type != 2:
            raise ValueError(f"channel {name}: pixel type {pixel_type}, expected FLOAT (2)")
        names.append(name)
        at = end + 1 + 16
    return names


def _unzip(raw):
    """OpenEXR's ZIP: zlib, then a delta predictor and two interleaved halves."""
    t = np.frombuffer(zlib.decompress(raw), dtype=np.uint8).astype(np.int32)
    t = (np.cumsum(t - 128 * (np.arange(t.size) > 0)) + 0) & 0xFF  # undo the predictor
    t = t.astype(np.uint8)
    half = (t.size + 1) // 2
    out = np.empty_like(t)
    out[0::2], out[1::2] = t[:half], t[half:]
    return out.tobytes()


def read_exr(path):
    data = open(path, "rb").read()
    if struct.unpack_from("<i", data, 0)[0] != 20000630:
        raise ValueError(f"{path}: not an OpenEXR file")
    attributes, at = _attributes(data, 8)
    names = _channels(attributes["channels"][1])
    compression = attributes["compression"][1][0]
    if compression not in _LINES_PER_CHUNK:
        raise ValueError(f"{path}: compression {compression} is not read here")
    x0, y0, x1, y1 = struct.unpack("<4i", attributes["dataWindow"][1])
    width, height = x1 - x0 + 1, y1 - y0 + 1
    lines = _LINES_PER_CHUNK[compression]
    chunks = (height + lines - 1) // lines
    offsets = struct.unpack_from(f"<{chunks}Q", data, at)
    image = np.zeros((height, width, len(names)), dtype=np.float32)
    for offset in offsets:
        y, size = struct.unpack_from("<ii", data, offset)
        raw = data[offset + 8:offset + 8 + size]
        count = min(lines, y1 + 1 - y)
        expected = count * width * 4 * len(names)
        block = raw if len(raw) == expected else _unzip(raw)
        values = np.frombuffer(block, dtype="<f4").reshape(count, len(names), width)
        image[y - y0:y - y0 + count] = values.transpose(0, 2, 1)
    return image, names
