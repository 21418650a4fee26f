#!/usr/bin/env python3
"""Writes the bad input files of scripts/bad-inputs.sh into the current directory.

Usage: bad-inputs.py BOARD FIXTURE_YAML FIXTURE_PGM

BOARD is a valid board file (boards/sim.json); FIXTURE_YAML/PGM a valid saved map
(fixtures/house-mid-mission.*). Every file is derived from them or written here; random bytes
come from a fixed seed, so two runs write the same files.
"""

import json
import os
import random
import struct
import sys
import zlib

RNG = random.Random(20)


def write(name, data):
    if isinstance(data, str):
        data = data.encode()
    with open(name, "wb") as f:
        f.write(data)


def garbage(n):
    return bytes(RNG.randrange(256) for _ in range(n))


def link(name, target):
    if os.path.lexists(name):
        os.remove(name)
    os.symlink(target, name)


def png(width, height, rows=None, depth=8, colour=0, idat=None):
    """A PNG of `width` x `height` grey pixels (`rows`: a list of byte rows, default all 255)."""

    def chunk(kind, body):
        return (
            struct.pack(">I", len(body))
            + kind
            + body
            + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF)
        )

    if idat is None:
        if rows is None:
            rows = [bytes([255]) * width for _ in range(height)]
        idat = zlib.compress(b"".join(b"\x00" + r for r in rows))
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, depth, colour, 0, 0, 0))
        + chunk(b"IDAT", idat)
        + chunk(b"IEND", b"")
    )


def boards(path):
    text = open(path).read()
    base = json.loads(text)

    def sub(name, old, new):
        assert old in text, old
        write(name, text.replace(old, new, 1))

    def edit(name, section, key, value):
        b = json.loads(text)
        if key is None:
            b[section] = value
        else:
            b[section][key] = value
        write(name, json.dumps(b, indent=2))

    def drop(name, section, key=None):
        b = json.loads(text)
        if key is None:
            del b[section]
        else:
            del b[section][key]
        write(name, json.dumps(b, indent=2))

    # Lexical: what json.dumps cannot write.
    sub("neg.json", '"population": 5', '"population": -5')
    sub("float.json", '"beam_count": 541', '"beam_count": 541.5')
    sub("str.json", '"baud": 9600', '"baud": "9600"')
    sub("bool.json", '"generations": 30', '"generations": true')
    sub("null.json", '"radius_m": 0.25', '"radius_m": null')
    sub("dup.json", '"seed": 1', '"seed": 1,\n    "seed": 2')
    sub("long.json", '"sim-p3dx"', '"' + "p" * 40 + '"')
    sub("big.json", '"population": 5', '"population": 70000')
    sub("e400.json", '"max_speed_mm_s": 400', '"max_speed_mm_s": 1e400')
    sub("nan.json", '"radius_m": 0.25', '"radius_m": NaN')
    sub("inf.json", '"step_deg": 0.5', '"step_deg": Infinity')
    sub("typo.json", '"population"', '"populaton"')
    sub("missing.json", '"coverage_target": 0.99,\n    "seed": 1', '"coverage_target": 0.99')
    sub("zeros.json", '"generations": 30', '"generations": 007')
    sub("plus.json", '"generations": 30', '"generations": +30')
    sub("hex.json", '"generations": 30', '"generations": 0x1e')
    sub("exp.json", '"generations": 30', '"generations": 3e1')
    sub("minus0.json", '"population": 5', '"population": -0')
    sub("u64.json", '"seed": 1', '"seed": 99999999999999999999999')
    sub("comment.json", '"seed": 1', '"seed": 1 // the seed')
    sub("quote.json", '"seed": 1', "'seed': 1")
    sub("comma.json", '"seed": 1', '"seed": 1,')
    sub("ctrl.json", '"sim-p3dx"', '"sim\tp3dx"')
    sub("surrogate.json", '"sim-p3dx"', '"\\ud800"')
    sub("escape.json", '"sim-p3dx"', '"sim\\qp3dx"')
    write("badutf8.json", text.replace('"sim-p3dx"', '"sim\xff"').encode("latin-1"))
    write("bom.json", b"\xef\xbb\xbf" + text.encode())
    write("utf16.json", text.encode("utf-16"))
    write("trailing.json", text + "}}")
    write("trunc.json", text[: len(text) // 2])
    write("empty.json", "")
    write("blank.json", " \n\t\n")
    write("random.json", garbage(2000))
    write("array.json", "[]")
    write("object.json", "{}")
    write("nulldoc.json", "null")
    write("number.json", "42")
    write("string.json", '"board"')
    write("deep.json", "[" * 60000)
    write("deepobj.json", '{"robot": ' * 5000)
    write("huge.json", text + " " * (70 << 10))
    # Structure and ranges (json.dumps).
    drop("nopid.json", "pid")
    drop("noport.json", "link", "port")
    edit("section-num.json", "robot", None, 5)
    edit("section-arr.json", "laser", None, [])
    edit("radius0.json", "robot", "radius_m", 0.0)
    edit("radiusneg.json", "robot", "radius_m", -0.25)
    edit("radius100.json", "robot", "radius_m", 100.0)
    edit("speed0.json", "robot", "max_speed_mm_s", 0)
    edit("speedbig.json", "robot", "max_speed_mm_s", 65535)
    edit("accel0.json", "robot", "accel_mm_s2", 0)
    edit("subclass.json", "robot", "subclass", "p3dx-xx")
    edit("baud.json", "link", "baud", 12345)
    edit("switchbaud.json", "link", "switch_to_baud", 1)
    edit("port-empty.json", "link", "port", "")
    edit("tcp-noport.json", "link", "tcp", "nohost")
    edit("tcp-bigport.json", "link", "tcp", "127.0.0.1:99999")
    edit("model.json", "laser", "model", "lms500")
    edit("beams0.json", "laser", "beam_count", 0)
    edit("beams-many.json", "laser", "beam_count", 60000)
    edit("step0.json", "laser", "step_deg", 0.0)
    edit("stepneg.json", "laser", "step_deg", -0.5)
    edit("range0.json", "laser", "max_range_m", 0.0)
    edit("range-order.json", "laser", "min_range_m", 10.0)
    edit("noise.json", "laser", "noise_fraction", 2.0)
    edit("rate0.json", "laser", "rate_hz", 0.0)
    edit("address.json", "laser", "address", "nohost")
    edit("address-empty.json", "laser", "address", "")
    b = json.loads(text)
    b["laser"]["model"] = "lms200"
    b["laser"].pop("address", None)
    write("lms200-noport.json", json.dumps(b, indent=2))
    b = json.loads(text)
    b["laser"]["mount"]["theta_deg"] = 1e9
    write("mount.json", json.dumps(b, indent=2))
    edit("width0.json", "grid", "width_m", 0.0)
    edit("width-huge.json", "grid", "width_m", 1e6)
    edit("res0.json", "grid", "resolution_m", 0.0)
    edit("res-tiny.json", "grid", "resolution_m", 1e-6)
    edit("origin.json", "grid", "origin_x_m", 1e30)
    edit("method.json", "mission", "method", "nope")
    edit("strategy.json", "mission", "strategy", "medium")
    edit("targets0.json", "mission", "targets", 0)
    b = json.loads(text)
    b["mission"]["strategy"] = "long"
    b["mission"]["targets"] = 1000
    write("targets-big.json", json.dumps(b, indent=2))
    edit("battery.json", "mission", "battery_steps", -1.0)
    edit("reserve.json", "mission", "reserve_steps", 1000.0)
    edit("coverage.json", "mission", "coverage_target", 1.5)
    edit("pop0.json", "mission", "population", 0)
    edit("gens0.json", "mission", "generations", 0)
    edit("kp.json", "pid", "heading_kp", -1.0)
    edit("kp-huge.json", "pid", "distance_kp", 1e30)
    edit("stop.json", "safety", "obstacle_stop_m", -1.0)
    edit("stale.json", "safety", "stale_timeout_s", 0.0)
    b = json.loads(text)
    b["robot"]["footprint"] = {"width_m": -0.4}
    write("footprint-width.json", json.dumps(b, indent=2))
    b = json.loads(text)
    b["robot"]["footprint"] = {"width_m": 0.6}
    write("footprint-swing.json", json.dumps(b, indent=2))
    b = json.loads(text)
    b["robot"]["footprint"] = {"width": 0.4}
    write("footprint-typo.json", json.dumps(b, indent=2))
    edit("clearance.json", "planning", None, {"clearance_m": 0.5})
    edit("clearance-neg.json", "planning", None, {"clearance_m": -0.05})
    edit("occupied-thresh.json", "mapping", None, {"occupied_thresh": 0.4})
    edit("occupied-thresh-one.json", "mapping", None, {"occupied_thresh": 1.0})
    edit("save0.json", "persistence", "save_every_s", 0.0)
    edit("saveneg.json", "persistence", "save_every_s", -2.0)
    return base


def states():
    """Log directories for `papillon run --resume`."""
    state = {
        "version": 1,
        "mission_time_s": 12.5,
        "pose": {"x_m": 1.0, "y_m": 1.0, "theta_rad": 0.0},
        "odom_pose": {"x_m": 1.0, "y_m": 1.0, "theta_rad": 0.0},
        "trajectory": [{"x_m": 1.0, "y_m": 1.0, "theta_rad": 0.0}],
        "counters": {
            "decisions": 1,
            "distance_m": 0.5,
            "energy_used_steps": 1.0,
            "faults": 0,
            "reconnects": 0,
            "scans": 10,
        },
        "coverage": 0.1,
        "finished": False,
    }

    def log(name, **files):
        os.makedirs(name, exist_ok=True)
        for f, data in files.items():
            write(os.path.join(name, f.replace("_", ".")), data)

    def state_with(**changes):
        s = json.loads(json.dumps(state))
        for k, v in changes.items():
            s[k] = v
        return json.dumps(s, indent=2)

    text = json.dumps(state, indent=2)
    os.makedirs("empty-log", exist_ok=True)
    log("garbage-state", state_json=garbage(3000))
    log("empty-state", state_json="")
    log("trunc-state", state_json=text[: len(text) // 2])
    log("version-state", state_json=state_with(version=99))
    log("type-state", state_json=state_with(coverage="high"))
    log("neg-state", state_json=state_with(counters=dict(state["counters"], decisions=-1)))
    log("array-state", state_json="[]")
    os.makedirs("dir-state/state.json", exist_ok=True)
    os.makedirs("zero-state", exist_ok=True)
    link("zero-state/state.json", "/dev/zero")
    os.makedirs("fifo-state", exist_ok=True)
    if not os.path.exists("fifo-state/state.json"):
        os.mkfifo("fifo-state/state.json")
    log("pgm-state", state_json=text, map_pgm=garbage(500), map_yaml=open(sys.argv[2]).read().replace("house-mid-mission.pgm", "map.pgm"))
    log("yaml-state", state_json=text, map_pgm=open(sys.argv[3], "rb").read(), map_yaml="image: [\n" + garbage(100).hex())
    log("time-state", state_json=state_with(mission_time_s=1e300))
    log("negtime-state", state_json=state_with(mission_time_s=-5.0))
    log("pose-state", state_json=state_with(pose={"x_m": 1e30, "y_m": -1e30, "theta_rad": 0.0}))
    log("unfinished", state_json=text)
    os.makedirs("telemetry-dir/telemetry.jsonl", exist_ok=True)
    write("afile", "not a directory\n")


def maps():
    # CSV (the thesis's format: 1 wall, 0 free, one line per metre row).
    row = lambda n, v="0": ",".join([v] * n)
    write("empty.csv", "")
    write("blank.csv", "\n\n\n")
    write("garbage.csv", garbage(1000))
    write("ragged.csv", "1,1,1,1\n1,0,0\n1,0,0,1\n1,1,1,1\n")
    write("two.csv", "\n".join([row(6, "1")] + ["1," + row(4) + ",2"] * 4 + [row(6, "1")]))
    write("neg.csv", "\n".join([row(6, "1")] + ["1," + row(4, "-1") + ",1"] * 4 + [row(6, "1")]))
    write("text.csv", "a,b,c\nd,e,f\n")
    write("one.csv", "0\n")
    write("walls.csv", "\n".join([row(24, "1")] * 24))
    write("wide.csv", row(200000, "0"))
    # PGM.
    write("magic.pgm", b"P9\n4 4\n255\n" + bytes(16))
    write("header.pgm", b"P5\n")
    write("huge.pgm", b"P5\n100000 100000\n255\n" + bytes(100))
    write("maxval0.pgm", b"P5\n4 4\n0\n" + bytes(16))
    write("maxval-big.pgm", b"P5\n4 4\n70000\n" + bytes(32))
    write("words.pgm", b"P2\n2 2\n255\nx y z w\n")
    write("over.pgm", b"P2\n2 2\n255\n300 0 0 0\n")
    write("negdim.pgm", b"P5\n-3 4\n255\n" + bytes(12))
    write("zerodim.pgm", b"P5\n0 0\n255\n")
    write("short.pgm", b"P5\n100 100\n255\n" + bytes(10))
    write("garbage.pgm", garbage(1000))
    # PNG.
    write("garbage.png", garbage(1000))
    good = png(80, 80)
    write("trunc.png", good[:60])
    write("big.png", png(20000, 20000, idat=zlib.compress(b"")))
    write("zerodim.png", png(0, 0, idat=zlib.compress(b"")))
    write("tiny.png", png(1, 1))
    write("baddata.png", png(80, 80, idat=b"not zlib at all"))
    write("depth.png", png(8, 8, depth=3))
    # Moving AI (.map) for worlds and `plan`.
    write("empty.map", "")
    write("noheader.map", "....\n....\n")
    write("huge.map", "type octile\nheight 100000000000\nwidth 100000000000\nmap\n....\n")
    write("negwidth.map", "type octile\nheight 4\nwidth -4\nmap\n....\n....\n....\n....\n")
    write("rows.map", "type octile\nheight 4\nwidth 4\nmap\n....\n..\n....\n")
    write("chars.map", "type octile\nheight 4\nwidth 4\nmap\n....\n.XY.\n....\n....\n")
    write("notype.map", "height 4\nwidth 4\nmap\n....\n....\n....\n....\n")
    write("width0.map", "type octile\nheight 4\nwidth 0\nmap\n\n\n\n\n")
    write("garbage.map", garbage(1000))
    grid = ["@" * 12] + ["@" + "." * 10 + "@"] * 10 + ["@" * 12]
    write("ok.map", "type octile\nheight 12\nwidth 12\nmap\n" + "\n".join(grid) + "\n")
    # Moving AI scenarios for `plan --map ok.map`.
    scen = lambda *lines: "version 1\n" + "".join(
        "0\tok.map\t12\t12\t" + l + "\n" for l in lines
    )
    write("ok.scen", scen("1\t1\t5\t5\t5.65685425"))
    write("empty.scen", "")
    write("noversion.scen", "0\tok.map\t12\t12\t1\t1\t5\t5\t5.6\n")
    write("fields.scen", "version 1\n0\tok.map\t12\n")
    write("outside.scen", scen("1\t1\t500\t5\t5.6"))
    write("negative.scen", scen("-1\t1\t5\t5\t5.6"))
    write("wall.scen", scen("0\t0\t5\t5\t5.6"))
    write("nan.scen", scen("1\t1\t5\t5\tnan"))
    write("words.scen", scen("a\tb\tc\td\te"))
    write("size.scen", "version 1\n0\tok.map\t99\t99\t1\t1\t5\t5\t5.6\n")
    write("garbage.scen", garbage(1000))
    # ROS map_server YAML (with the fixture's PGM beside it).
    pgm = open(sys.argv[3], "rb").read()
    write("ok.pgm", pgm)
    y = "image: ok.pgm\nresolution: 0.1\norigin: [0, 0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\nmode: trinary\n"
    write("ok.yaml", y)

    def yaml(name, old, new):
        assert old in y, old
        write(name, y.replace(old, new, 1))

    yaml("noimage.yaml", "image: ok.pgm\n", "")
    yaml("lost.yaml", "ok.pgm", "lost.pgm")
    yaml("self.yaml", "ok.pgm", "self.yaml")
    link("zero.pgm", "/dev/zero")
    yaml("zeroimg.yaml", "ok.pgm", "zero.pgm")
    os.makedirs("dir.pgm", exist_ok=True)
    yaml("dirimg.yaml", "ok.pgm", "dir.pgm")
    yaml("emptyimg.yaml", "image: ok.pgm", "image: ")
    yaml("garbageimg.yaml", "ok.pgm", "garbage.pgm")
    yaml("res.yaml", "resolution: 0.1", "resolution: 1e30")
    yaml("resneg.yaml", "resolution: 0.1", "resolution: -0.1")
    yaml("res0.yaml", "resolution: 0.1", "resolution: 0")
    yaml("resnan.yaml", "resolution: 0.1", "resolution: .nan")
    yaml("resword.yaml", "resolution: 0.1", "resolution: fine")
    yaml("nores.yaml", "resolution: 0.1\n", "")
    yaml("origin.yaml", "origin: [0, 0, 0.0]", "origin: [1e9, 0.0, 0.0]")
    yaml("origin2.yaml", "origin: [0, 0, 0.0]", "origin: [0, 0]")
    yaml("originword.yaml", "origin: [0, 0, 0.0]", "origin: [east, north, 0]")
    yaml("yaw.yaml", "origin: [0, 0, 0.0]", "origin: [0, 0, 0.5]")
    yaml("negate.yaml", "negate: 0", "negate: 2")
    yaml("occ.yaml", "occupied_thresh: 0.65", "occupied_thresh: 2")
    yaml("thresh.yaml", "free_thresh: 0.196", "free_thresh: 0.9")
    yaml("mode.yaml", "mode: trinary", "mode: weird")
    yaml("dupkey.yaml", "negate: 0", "negate: 0\nnegate: 1")
    yaml("tabs.yaml", "resolution: 0.1", "resolution:\t\t[0.1")
    write("garbage.yaml", garbage(1000))
    write("empty.yaml", "")
    write("huge.yaml", y + "#" * (2 << 20))
    os.makedirs("dir.yaml", exist_ok=True)
    link("zero.png", "/dev/zero")
    link("zero.csv", "/dev/zero")
    link("zero.map", "/dev/zero")
    os.makedirs("dir.png", exist_ok=True)
    if not os.path.exists("fifo.csv"):
        os.mkfifo("fifo.csv")
    write("x.bmp", b"BM")
    write("noext", "0,0\n")


def sweeps():
    ok = {"maps": ["lab"], "methods": ["nearest-frontier"], "runs": 1, "generations": 2}

    def sweep(name, **changes):
        s = dict(ok)
        s.update(changes)
        write(name, json.dumps(s))

    sweep("ok-sweep.json")
    write("sweep-garbage.json", garbage(1000))
    write("sweep-empty.json", "")
    write("sweep-array.json", "[]")
    write("sweep-trunc.json", json.dumps(ok)[:20])
    sweep("sweep-type.json", runs="ten")
    sweep("sweep-unknown.json", run=1)
    sweep("sweep-nomaps.json", maps=[])
    sweep("sweep-method.json", methods=["nope"])
    sweep("sweep-map.json", maps=["nowhere"])
    sweep("sweep-strategy.json", strategies=[{"name": "medium"}])
    sweep("sweep-pop0.json", populations=[0])
    sweep("sweep-robots0.json", robots=[0])
    sweep("sweep-robots101.json", robots=[101])
    sweep("sweep-runs0.json", runs=0)
    sweep("sweep-runs-huge.json", runs=10**12)
    sweep("sweep-gens.json", generations=-1)
    sweep("sweep-res0.json", resolution_m=0.0)
    sweep("sweep-res-tiny.json", resolution_m=1e-9)
    sweep("sweep-res-big.json", resolution_m=100.0)
    sweep("sweep-battery.json", battery_steps=-1.0)
    sweep("sweep-seed.json", base_seed=-1)
    sweep("sweep-objective.json", objective="greedy")
    # Shard directories for `bench merge`.
    os.makedirs("shard-empty", exist_ok=True)
    os.makedirs("shard-garbage", exist_ok=True)
    write("shard-garbage/sweep.json", garbage(500))
    write("shard-garbage/runs.jsonl", garbage(500))
    os.makedirs("shard-runs", exist_ok=True)
    write("shard-runs/sweep.json", json.dumps(dict(ok, name="s")))
    write("shard-runs/runs.jsonl", '{"index": 0, "status": \n' + garbage(200).hex() + "\n")
    os.makedirs("shard-other", exist_ok=True)
    write("shard-other/sweep.json", json.dumps(dict(ok, name="other", runs=2)))
    write("shard-other/runs.jsonl", "")


def main():
    boards(sys.argv[1])
    states()
    maps()
    sweeps()


main()
