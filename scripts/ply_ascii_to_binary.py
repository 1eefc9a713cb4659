#!/usr/bin/env python3
"""Converts an ASCII PLY mesh to binary little-endian PLY with the same header and geometry.

Usage: scripts/ply_ascii_to_binary.py IN.ply OUT.ply

The header is kept line for line except the format line. Scalar properties keep their declared
types; a float32 value is rounded from its decimal text exactly (round half to even), the way
a correctly rounding reader such as datasets/src/ply_reader.cpp (std::from_chars to float) reads
it, so the binary file holds the very numbers the ASCII one stands for. Python 3 stdlib only.
"""
import decimal
import struct
import sys

# struct format and integer-ness per PLY type name (both spellings).
TYPES = {
    "char": "b", "int8": "b", "uchar": "B", "uint8": "B",
    "short": "h", "int16": "h", "ushort": "H", "uint16": "H",
    "int": "i", "int32": "i", "uint": "I", "uint32": "I",
    "float": "f", "float32": "f", "double": "d", "float64": "d",
}

decimal.getcontext().prec = 60  # more than any float32 midpoint needs


def float32_from_text(text):
    """The float32 nearest to the decimal `text` (ties to even), as struct packs it."""
    exact = decimal.Decimal(text)
    guess = struct.unpack("<f", struct.pack("<f", float(text)))[0]  # via double: may be 1 ulp off
    bits = struct.unpack("<I", struct.pack("<f", guess))[0]
    candidates = [guess]
    for step in (-1, 1):
        neighbour_bits = bits + step
        if 0 <= neighbour_bits < 2**32:
            neighbour = struct.unpack("<f", struct.pack("<I", neighbour_bits))[0]
            if neighbour == neighbour:  # not NaN
                candidates.append(neighbour)

    def key(value):
        even = struct.unpack("<I", struct.pack("<f", value))[0] % 2
        return (abs(decimal.Decimal(value) - exact), even)

    return min(candidates, key=key)


def pack_value(type_name, text, where):
    code = TYPES[type_name]
    if code == "f":
        return struct.pack("<f", float32_from_text(text))
    if code == "d":
        return struct.pack("<d", float(text))
    try:
        return struct.pack("<" + code, int(text))
    except (ValueError, struct.error) as error:
        raise SystemExit(f"{where}: '{text}' is not a {type_name}: {error}")


def convert(in_path, out_path):
    with open(in_path, "rb") as stream:
        data = stream.read()
    end = data.find(b"end_header\n")
    if not data.startswith(b"ply\n") or end < 0:
        raise SystemExit(f"{in_path}: not a PLY file with an end_header line")
    header_lines = data[: end + len(b"end_header\n")].decode("ascii").splitlines()
    body = data[end + len(b"end_header\n") :].decode("ascii").split("\n")

    elements = []  # (name, count, [(name, type, count_type or None)])
    out_header = []
    for line in header_lines:
        tokens = line.split()
        if tokens[:1] == ["format"]:
            if tokens[1] != "ascii":
                raise SystemExit(f"{in_path}: format is {tokens[1]}, expected ascii")
            line = "format binary_little_endian 1.0"
        elif tokens[:1] == ["element"]:
            elements.append((tokens[1], int(tokens[2]), []))
        elif tokens[:2] == ["property", "list"]:
            elements[-1][2].append((tokens[4], tokens[3], tokens[2]))
        elif tokens[:1] == ["property"]:
            elements[-1][2].append((tokens[2], tokens[1], None))
        out_header.append(line)

    out = bytearray(("\n".join(out_header) + "\n").encode("ascii"))
    row = 0
    for name, count, properties in elements:
        for index in range(count):
            where = f"{in_path}: {name} {index} (body line {row + 1})"
            if row >= len(body):
                raise SystemExit(f"{where}: file ends early")
            tokens = body[row].split()
            row += 1
            position = 0
            for prop_name, type_name, count_type in properties:
                if position >= len(tokens):
                    raise SystemExit(f"{where}: no value for {prop_name}")
                if count_type is None:
                    out += pack_value(type_name, tokens[position], where)
                    position += 1
                    continue
                items = int(tokens[position])
                out += pack_value(count_type, tokens[position], where)
                values = tokens[position + 1 : position + 1 + items]
                if len(values) != items:
                    raise SystemExit(f"{where}: list {prop_name} has fewer than {items} items")
                for value in values:
                    out += pack_value(type_name, value, where)
                position += 1 + items
            if position != len(tokens):
                raise SystemExit(f"{where}: {len(tokens) - position} values left over")
    if any(line.strip() for line in body[row:]):
        raise SystemExit(f"{in_path}: data after the last element")
    with open(out_path, "wb") as stream:
        stream.write(out)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        raise SystemExit(__doc__.strip().splitlines()[2])
    convert(sys.argv[1], sys.argv[2])
