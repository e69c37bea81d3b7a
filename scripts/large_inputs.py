#!/usr/bin/env python3
"""Writes the large inputs the memory figures of crates/petri/BENCHMARKS.md,
crates/sim/BENCHMARKS.md and crates/guide/BENCHMARKS.md are measured on (peak memory to read a net, a map or a mission log: at most
10 times the file's size plus a constant, docs/inputs.md):

    scripts/large_inputs.py DIR [MB]      (default 50 MB each)

In DIR: net.toml, net.pnml, net.PNPRO (places, transitions and arcs of a
ring, and at the very end an arc to a place that does not exist, so that
reading goes through the whole file and ends with its error), map.yaml and
map.pgm (a binary PGM of about MB megabytes, a wall every 50 rows), and
log.jsonl (the crediting supervisor's mission log: two calibration runs,
then missions numbered 1, 2, …; `net` is the placeholder
`{credit_net}`, replaced by the id PETRINAV_CREDIT_NET names, else left as
it is — `guide log show` then stops at line 1, another net's log).

Then, for each, the peak resident memory (`/usr/bin/time -v`, "Maximum
resident set size"):

    /usr/bin/time -v target/release/petrinav gspn info DIR/net.toml
    /usr/bin/time -v target/release/petrinav map info DIR/map.yaml
    /usr/bin/time -v target/release/petrinav guide log show DIR/log.jsonl > /dev/null
"""

import math
import os
import sys


def fill(f, until, item):
    """Writes item(0), item(1), ... to f until it holds `until` bytes;
    returns how many were written."""
    n = 0
    while f.tell() < until:
        f.write(item(n))
        n += 1
    return n


def net_files(d, size):
    with open(os.path.join(d, "net.toml"), "w") as f:
        f.write('name = "big"\n[params]\nlambda = 1.0\n')
        places = fill(f, size // 2, lambda i: f'[[place]]\nname = "P{i}"\ninitial = 1\n')
        fill(
            f,
            size,
            lambda j: f'[[transition]]\nname = "T{j}"\nrate = "lambda"\n'
            f'inputs = ["P{j % places}"]\noutputs = ["P{(j + 1) % places}"]\n',
        )
        f.write('[[transition]]\nname = "Tbad"\nrate = "lambda"\ninputs = ["nowhere"]\n')
    with open(os.path.join(d, "net.pnml"), "w") as f:
        f.write(
            '<?xml version="1.0" encoding="UTF-8"?>\n'
            '<pnml xmlns="http://www.pnml.org/version-2009/grammar/pnml">\n'
            '<net id="big" type="http://www.pnml.org/version-2009/grammar/ptnet">\n<page id="page0">\n'
        )
        places = fill(
            f,
            size * 2 // 5,
            lambda i: f'<place id="P{i}"><initialMarking><text>1</text></initialMarking></place>\n',
        )
        fill(
            f,
            size,
            lambda j: f'<transition id="T{j}"/>\n<arc id="a{2 * j}" source="P{j % places}" target="T{j}"/>\n'
            f'<arc id="a{2 * j + 1}" source="T{j}" target="P{(j + 1) % places}"/>\n',
        )
        f.write('<arc id="bad" source="nowhere" target="T0"/>\n</page>\n</net>\n</pnml>\n')
    with open(os.path.join(d, "net.PNPRO"), "w") as f:
        f.write(
            '<?xml version="1.0" encoding="UTF-8" standalone="no"?>\n'
            '<project name="big" version="121">\n<gspn name="big">\n<nodes>\n'
        )
        places = fill(f, size * 3 // 10, lambda i: f'<place name="P{i}" marking="1" x="2" y="2"/>\n')
        transitions = fill(
            f,
            size * 56 // 100,
            lambda j: f'<transition name="T{j}" type="EXP" delay="1" nservers="1" x="6" y="10"/>\n',
        )
        f.write("</nodes>\n<edges>\n")
        fill(
            f,
            size,
            lambda k: f'<arc head="T{k % transitions}" kind="INPUT" tail="P{k % places}"/>\n'
            f'<arc head="P{(k + 1) % places}" kind="OUTPUT" tail="T{k % transitions}"/>\n',
        )
        f.write('<arc head="T0" kind="INPUT" tail="nowhere"/>\n</edges>\n</gspn>\n</project>\n')


def map_files(d, size):
    side = int(math.sqrt(size))
    with open(os.path.join(d, "map.pgm"), "wb") as f:
        f.write(b"P5\n%d %d\n255\n" % (side, side))
        free, wall = bytes([254] * side), bytes([0] * side)
        for y in range(side):
            f.write(wall if y % 50 == 0 else free)
    with open(os.path.join(d, "map.yaml"), "w") as f:
        f.write(
            "image: map.pgm\nresolution: 0.05\norigin: [0.0, 0.0, 0.0]\n"
            "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"
        )


def log_file(d, size):
    net = os.environ.get("PETRINAV_CREDIT_NET", "{credit_net}")
    trajectory = ",".join(f"[8.1,{6.4 + 0.5 * k:.1f}]" for k in range(43))
    calibration = (
        '{{"net":"{net}","kind":"calibration","behaviour":"{b}","success":true,'
        '"duration_s":{t},"path_m":21.5,"trajectory":[{trajectory}],"outcome":"goal",'
        '"segments":[{{"behaviour":"{b}","localized":true,"normal":true,"context":0,'
        '"duration_s":{t},"progress_m":null,"end":"mission"}}]}}\n'
    )
    mission = (
        '{{"net":"{net}","kind":"mission","mission":{k},"success":true,"outcome":"goal",'
        '"duration_s":49.9,"localizer":[{{"state":"success","duration_s":49.9,"ended":false}}],'
        '"planner":[{{"state":"normal","duration_s":49.9,"ended":false}}],'
        '"time_automove_s":49.8,"time_contour_s":0.0,"decisions":[{{"time_s":0.0,"reason":"start",'
        '"rates":[0.001,1000.0,0.001,0.1,0.001,1000.0,0.02,0.011,0.001,0.001,1000.0,0.001,0.0001,0.0001,0.0033],'
        '"f_auto":0.0192,"f_cont":0.0108,"p_loc_succ":0.99,"p_loc_warn":0.01,"choice":"automove","context":0}}],'
        '"segments":[{{"behaviour":"automove","localized":true,"normal":true,"context":0,'
        '"duration_s":49.8,"progress_m":23.9,"end":"mission"}}]}}\n'
    )
    with open(os.path.join(d, "log.jsonl"), "w") as f:
        f.write(calibration.format(net=net, b="automove", t=49.9, trajectory=trajectory))
        f.write(calibration.format(net=net, b="contour", t=89.1, trajectory=trajectory))
        fill(f, size, lambda k: mission.format(net=net, k=k + 1))


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    d = sys.argv[1]
    size = int(float(sys.argv[2]) * 1_000_000) if len(sys.argv) > 2 else 50_000_000
    os.makedirs(d, exist_ok=True)
    net_files(d, size)
    map_files(d, size)
    log_file(d, size)
    for name in sorted(os.listdir(d)):
        print(f"{os.path.join(d, name)}  {os.path.getsize(os.path.join(d, name)):,} bytes")


if __name__ == "__main__":
    main()
