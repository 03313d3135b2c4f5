#!/usr/bin/env python3
"""A remote vas client written from docs/wire.md alone, on the Python zenoh package.

It reads the byte layouts from the specification's tables (so it trusts nothing but the
document), meets a vas-bridge (connecting to it, or listening for it to connect), and checks
what a renderer and an input device on another machine do: it fetches the geometry with a query
and decodes every mesh, decodes parts and hand frames, sends one user's hand joints and sees that
hand follow, sends bytes of the wrong size and version (and of a stray user) and sees the bridge
count them, and resets the scene through the control queryable. Any failure ends it with a
message and exit status 1; success prints a JSON summary.

    remote_client.py --connect tcp/127.0.0.1:7447 --session S --spec docs/wire.md \
        --recording tests/fixtures/captured_relaxed_approach.jsonl
"""

import argparse
import json
import queue
import re
import struct
import sys
import time

import zenoh

NUMBERS = {"u8": "B", "u32": "I", "u64": "Q", "f32": "f", "f64": "d"}
PATIENCE = 30.0


class Spec:
    """The types of docs/wire.md: each one's size and fields, and the envelope's codes."""

    def __init__(self, path):
        self.types = {}
        self.codes = {}
        current = None
        section = None
        with open(path, encoding="utf-8") as spec:
            for line in spec:
                line = line.rstrip("\n")
                if line.startswith("## "):
                    section, current = line[3:].strip(), None
                    continue
                if line.startswith("### "):
                    current = line[4:].strip().strip("`")
                    self.types[current] = {"size": None, "fields": []}
                    continue
                cells = [cell.strip().strip("`") for cell in line.strip().strip("|").split("|")]
                if not line.startswith("|") or not cells[0].isdigit():
                    size = re.match(r"`(\w+)`: (\d+) bytes, alignment (\d+)", line)
                    if size and size.group(1) in self.types:
                        self.types[size.group(1)]["size"] = int(size.group(2))
                    continue
                if current:
                    self.types[current]["fields"].append((int(cells[0]), cells[1], cells[2]))
                elif section == "Envelope":
                    self.codes[cells[1]] = (int(cells[0]), int(cells[2]))

    def size(self, name):
        return self.types[name]["size"]

    def _kind(self, spelling):
        match = re.fullmatch(r"(\w+)(?:\[(\d+)\])?", spelling)
        return match.group(1), int(match.group(2) or 1)

    def unpack(self, name, data, base=0):
        """A dict of the fields of type `name` at `base`; texts as str, nested types as dicts."""
        fields = {}
        for offset, field, spelling in self.types[name]["fields"]:
            kind, count = self._kind(spelling)
            at = base + offset
            if kind in NUMBERS:
                values = struct.unpack_from("<%d%s" % (count, NUMBERS[kind]), data, at)
                value = list(values) if count > 1 or "[" in spelling else values[0]
            else:
                step = self.size(kind)
                value = [self.unpack(kind, data, at + i * step) for i in range(count)]
                value = value if "[" in spelling else value[0]
            fields[field] = value
        if name.startswith("Text"):
            return bytes(fields["bytes"][: fields["len"]]).decode("utf-8")
        return fields

    def pack_into(self, name, buffer, base, values):
        """Writes the fields of `values` (a dict, texts as str) of type `name` at `base`."""
        if name.startswith("Text"):
            encoded = values.encode("utf-8")
            values = {"len": len(encoded), "bytes": list(encoded)}
        for offset, field, spelling in self.types[name]["fields"]:
            if field not in values:
                continue
            kind, count = self._kind(spelling)
            value = values[field]
            if kind in NUMBERS:
                items = value if isinstance(value, list) else [value]
                layout = "<%d%s" % (len(items), NUMBERS[kind])
                struct.pack_into(layout, buffer, base + offset, *items)
            else:
                items = value if isinstance(value, list) else [value]
                for i, item in enumerate(items):
                    self.pack_into(kind, buffer, base + offset + i * self.size(kind), item)

    def message(self, name, values):
        """The envelope and body of a message of body type `name`."""
        code, version = self.codes[name]
        buffer = bytearray(8 + self.size(name))
        struct.pack_into("<II", buffer, 0, code, version)
        self.pack_into(name, buffer, 8, values)
        return bytes(buffer)

    def open(self, name, payload):
        """The body of a message, after checking its envelope."""
        code, version = struct.unpack_from("<II", payload, 0)
        check((code, version) == self.codes[name], f"{name} envelope {(code, version)}")
        return payload[8:]


def check(condition, message):
    if not condition:
        print(f"remote client: FAILED: {message}", file=sys.stderr)
        sys.exit(1)


def say(message):
    print(f"remote client: {message}", file=sys.stderr, flush=True)


class Reader:
    """Walks the geometry payload's grammar (docs/wire.md, Geometry)."""

    def __init__(self, data):
        self.data, self.at = data, 0

    def u32(self):
        (value,) = struct.unpack_from("<I", self.data, self.at)
        self.at += 4
        return value

    def name(self):
        length = self.u32()
        text = bytes(self.data[self.at : self.at + length]).decode("utf-8")
        self.at += (length + 3) // 4 * 4
        return text

    def mesh(self):
        name = self.name()
        vertices, triangles, normals, zero = (self.u32() for _ in range(4))
        check(normals in (0, 1) and zero == 0, f"mesh {name} header")
        floats = struct.unpack_from("<%df" % (3 * vertices), self.data, self.at)
        self.at += 12 * vertices * (1 + normals)
        indices = struct.unpack_from("<%dI" % (3 * triangles), self.data, self.at)
        self.at += 12 * triangles
        check(all(index < vertices for index in indices), f"mesh {name} indices")
        return {"name": name, "vertices": vertices, "triangles": triangles, "first": floats[:3]}


def decode_geometry(spec, payload):
    body = spec.open("GeometryHeader", payload)
    header = spec.unpack("GeometryHeader", body)
    data = memoryview(body)[spec.size("GeometryHeader") :]
    check(len(data) == header["byte_len"], "geometry byte_len")
    reader = Reader(data)
    parts = [reader.mesh() for _ in range(header["part_count"])]
    hands = []
    for _ in range(header["hand_count"]):
        user, side, segments = reader.u32(), reader.u32(), reader.u32()
        model = reader.name()
        hands.append({"user": user, "side": side, "model": model,
                      "segments": [reader.mesh() for _ in range(segments)]})
    check(reader.at == len(data), "geometry ends with its last mesh")
    return header["generation"], parts, hands


def decode_parts(spec, payload):
    body = spec.open("PartsFrameHeader", payload)
    header = spec.unpack("PartsFrameHeader", body)
    step, first = spec.size("PartState"), spec.size("PartsFrameHeader")
    check(len(body) == first + step * header["part_count"], "parts frame length")
    parts = [spec.unpack("PartState", body, first + i * step) for i in range(header["part_count"])]
    return header, parts


def unit(quaternion):
    return abs(sum(v * v for v in quaternion) - 1.0) < 1e-6


class Remote:
    def __init__(self, args, spec):
        self.args, self.spec = args, spec
        config = zenoh.Config()
        config.insert_json5("mode", '"peer"')
        if args.connect:
            config.insert_json5("connect/endpoints", json.dumps([args.connect]))
        else:
            config.insert_json5("listen/endpoints", json.dumps([args.listen]))
        config.insert_json5("scouting/multicast/enabled", "false")
        self.session = zenoh.open(config)
        self.root = f"vas/{args.session}"
        self.queues = {}
        self.subscribers = [self.subscribe(key) for key in
                            ("scene/geometry", "output/parts", "output/hand", "output/events")]
        self.joints = self.session.declare_publisher(f"{self.root}/input/hand_joints")

    def subscribe(self, key):
        inbox = self.queues.setdefault(key, queue.Queue())
        return self.session.declare_subscriber(
            f"{self.root}/{key}", lambda sample: inbox.put(sample.payload.to_bytes()))

    def next(self, key, accept, what):
        deadline = time.monotonic() + PATIENCE
        while time.monotonic() < deadline:
            try:
                payload = self.queues[key].get(timeout=max(0.0, deadline - time.monotonic()))
            except queue.Empty:
                break
            found = accept(payload)
            if found is not None:
                return found
        check(False, f"no {what} within {PATIENCE} s")

    def query(self, key, payload=None):
        """The replies' payloads: ('ok' or 'err', bytes) each."""
        replies = self.session.get(f"{self.root}/{key}", payload=payload, timeout=PATIENCE)
        return [("ok", r.ok.payload.to_bytes()) if r.ok else ("err", r.err.payload.to_bytes())
                for r in replies]

    def control(self, kind, argument=0, text=""):
        fields = {"kind": kind, "argument": argument, "path": text}
        request = self.spec.message("ControlRequest", fields)
        replies = self.query("control", request)
        check(len(replies) == 1 and replies[0][0] == "ok", f"control {kind}: {replies}")
        return self.spec.unpack("ControlResponse", self.spec.open("ControlResponse", replies[0][1]))

    def stats(self):
        replies = self.query("bridge/stats")
        check(len(replies) == 1 and replies[0][0] == "ok", f"bridge stats: {replies}")
        return json.loads(replies[0][1])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    peer = parser.add_mutually_exclusive_group(required=True)
    peer.add_argument("--connect", help="the bridge's endpoint")
    peer.add_argument("--listen", help="an endpoint to listen on, for a bridge to connect to")
    parser.add_argument("--session", required=True)
    parser.add_argument("--spec", required=True)
    parser.add_argument("--recording", required=True)
    parser.add_argument("--stray-user", type=int,
                        help="a user the bridge does not take input for: a sample of it is refused")
    args = parser.parse_args()
    spec = Spec(args.spec)
    remote = Remote(args, spec)

    # A renderer that joins late fetches the geometry.
    replies = []
    deadline = time.monotonic() + PATIENCE
    while not replies and time.monotonic() < deadline:
        replies = remote.query("scene/geometry")
        time.sleep(0.05 if not replies else 0)
    check(len(replies) == 1 and replies[0][0] == "ok", f"geometry query: {replies}")
    generation, parts, hands = decode_geometry(spec, replies[0][1])
    check(parts and hands and hands[0]["segments"], "meshes of parts and hand segments")
    say(f"geometry {generation}: {len(parts)} parts, {len(hands)} hands")

    info = remote.control(1)  # SceneInfo
    check(info["status"] == 0 and info["generation"] == generation, f"scene info {info['status']}")
    check(info["part_count"] == len(parts), "the scene info counts the geometry's parts")
    users = [info["users"][i] for i in range(info["user_count"])]

    # One user's hand joints, from a captured hand, raised 3 cm step by step: the hand follows.
    with open(args.recording, encoding="utf-8") as recording:
        lines = (line for line in recording if '"hand_joints"' in line)
        sample = json.loads(next(lines))["hand_joints"]
    seq = 0

    def send(lift):
        nonlocal seq
        seq += 1
        joints = [{**joint, "position": [x, y, z + lift]}
                  for joint in sample["joints"] for x, y, z in [joint["position"]]]
        remote.joints.put(spec.message("HandJointsSample", {
            "seq": seq, "timestamp_ns": time.time_ns(), "joints": joints,
            "side": sample["side"], "user": 0}))
        wanted = seq

        def answers(payload):
            frame = spec.unpack("HandFrame", spec.open("HandFrame", payload))
            return frame if frame["joints"]["seq"] == wanted and frame["user"] == 0 else None

        return remote.next("output/hand", answers, f"hand frame answering sample {wanted}")

    first = send(0.0)
    check(first["tracked"] == 1 and first["segment_count"] == len(hands[0]["segments"]), "tracked")
    check(unit(first["root"]["rotation"]), "the root's rotation is a unit quaternion")
    frame = first
    for _ in range(40):
        previous = frame["root"]["position"]
        frame = send(0.03)
        if max(abs(a - b) for a, b in zip(frame["root"]["position"], previous)) < 1e-5:
            break
    moved = [b - a for a, b in zip(first["root"]["position"], frame["root"]["position"])]
    check(abs(moved[0]) < 1e-3 and abs(moved[1]) < 1e-3 and abs(moved[2] - 0.03) < 1e-3,
          f"the hand followed the joints 3 cm up: moved {moved}")
    say(f"the hand followed: root moved {moved} in {seq} samples")

    # Parts frames decode, one pose per part.
    header, states = decode_parts(spec, remote.next("output/parts", lambda p: p, "parts frame"))
    check(len(states) == len(parts) and all(unit(s["rotation"]) for s in states), "parts frame")

    # Bytes of the wrong size and version are refused and counted; the bridge goes on.
    before = remote.stats()
    good = bytearray(spec.message("HandJointsSample", {"seq": 999, "side": 0}))
    remote.joints.put(bytes(good[:-4]))
    struct.pack_into("<I", good, 4, spec.codes["HandJointsSample"][1] + 1)
    remote.joints.put(bytes(good))
    deadline = time.monotonic() + PATIENCE
    while time.monotonic() < deadline:
        after = remote.stats()
        if after["refused_size"] > before["refused_size"] and \
                after["refused_version"] > before["refused_version"]:
            break
        time.sleep(0.05)
    check(after["refused_size"] == before["refused_size"] + 1, f"size refusals {after}")
    check(after["refused_version"] == before["refused_version"] + 1, f"version refusals {after}")
    check(after["hand_joints_forwarded"] >= seq, "every good sample was forwarded")
    if args.stray_user is not None:
        stray = dict(sample, seq=seq + 1, timestamp_ns=time.time_ns(), user=args.stray_user)
        remote.joints.put(spec.message("HandJointsSample", stray))
        deadline = time.monotonic() + PATIENCE
        while remote.stats()["refused_user"] == after["refused_user"]:
            check(time.monotonic() < deadline, "the stray user's sample is refused and counted")
            time.sleep(0.05)
        after = remote.stats()
        check(after["hand_joints_forwarded"] == before["hand_joints_forwarded"],
              "the stray user's sample was not forwarded")

    # A reset through the control queryable: a new generation, and its geometry is published.
    reset = remote.control(4)  # Reset
    check(reset["status"] == 0 and reset["kind"] == 4, f"reset answered {reset['status']}")
    check(reset["generation"] > generation, "a reset makes a new generation")
    new_generation = remote.next(
        "scene/geometry",
        lambda payload: decode_geometry(spec, payload)[0] if
        decode_geometry(spec, payload)[0] == reset["generation"] else None,
        "geometry of the reset scene")
    refused = remote.query("control", spec.message("ControlRequest", {"kind": 3, "path": "/etc/x"}))
    check(len(refused) == 1 and refused[0][0] == "err", "a load by path is refused")

    print(json.dumps({
        "generation": generation, "reset_generation": new_generation, "parts": len(parts),
        "hands": len(hands), "users": users, "samples": seq, "moved": moved,
        "parts_frame": header["frame"], "bridge": after,
    }))


if __name__ == "__main__":
    main()
