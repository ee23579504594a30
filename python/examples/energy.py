"""Runs a scene in-process, plots its energy history with matplotlib and prints the summary.

    pip install ./python matplotlib pandas
    python python/examples/energy.py [SCENE] [--backend auto|cpu|gpu] [--velocity V]

By default the two steel rods of assets/rods_impact.toml; --velocity overrides the striker's
impact velocity (the key path `body[striker].initial_velocity[0]`, as a study varies it). The
picture is written beside the outputs (out/<scene>/energy.png).
"""

import argparse
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # no display needed
import matplotlib.pyplot as plt

import ricochet

REPO = Path(__file__).resolve().parents[2]

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("scene", nargs="?", default=REPO / "assets" / "rods_impact.toml")
parser.add_argument("--backend", default="auto")
parser.add_argument("--velocity", type=float)
args = parser.parse_args()

scene = ricochet.Scene.load(args.scene)
if args.velocity is not None:
    scene.set("body[striker].initial_velocity[0]", args.velocity)
plan = scene.check()
print(f"{scene.name}: {plan['nodes']} nodes, {plan['elements']} elements, about {plan['steps']} steps")

result = scene.run(backend=args.backend)  # Ctrl-C stops it with an "interrupted" summary

h = result.history
fig, ax = plt.subplots(figsize=(7, 4))
for column in ["kinetic_energy", "internal_energy", "contact_energy"]:
    ax.plot(h["time"] * 1e6, h[column], label=column.replace("_", " "))
ax.set_xlabel("time (us)")
ax.set_ylabel("energy (J)")
ax.set_title(f"{scene.name}: {result.summary['status']} on {result.summary['backend']}")
ax.legend()
fig.tight_layout()
picture = result.out / "energy.png"
fig.savefig(picture, dpi=120)

print(json.dumps(result.summary, indent=2))
print(f"energy history drawn in {picture}")
