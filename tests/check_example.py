#!/usr/bin/env python3
"""Run one example scene through the tdcr CLI and compare its answer with the expected output
stored beside the examples (examples/expected/NAME.json), the way SUNDIALS' examples carry answer
files.

usage: check_example.py TDCR_EXE SCENE EXPECTED [--update]

Checks the status, the model, the tip pose (position to 1e-9 m, rotation to 1e-8) and every tendon
displacement (to 1e-9 m). --update rewrites EXPECTED from the current output instead.
"""
import json
import subprocess
import sys

exe, scene, expected_path = sys.argv[1:4]
update = "--update" in sys.argv[4:]
run = subprocess.run([exe, "solve", scene, "--json"], capture_output=True, text=True)
if run.returncode not in (0, 1):
    sys.exit(f"tdcr exited {run.returncode}: {run.stderr}")
out = json.loads(run.stdout)
answer = {
    "model": out["model"],
    "status": out["status"],
    "tip": out["tip"],
    "tendon_displacements": out["tendon_displacements"],
}
if update:
    with open(expected_path, "w") as f:
        json.dump(answer, f, indent=1)
        f.write("\n")
    print(f"updated {expected_path}")
    sys.exit(0)
with open(expected_path) as f:
    exp = json.load(f)
errors = []
if answer["model"] != exp["model"]:
    errors.append(f"model {answer['model']} != {exp['model']}")
if answer["status"] != exp["status"]:
    errors.append(f"status {answer['status']} != {exp['status']}: {out['reason']}")
dp = max(abs(a - b) for a, b in zip(answer["tip"]["position"], exp["tip"]["position"]))
dr = max(abs(a - b) for ra, rb in zip(answer["tip"]["rotation"], exp["tip"]["rotation"]) for a, b in zip(ra, rb))
dd = max([abs(a - b) for a, b in zip(answer["tendon_displacements"], exp["tendon_displacements"])] or [0.0])
if dp > 1e-9:
    errors.append(f"tip position differs by {dp:.3g} m")
if dr > 1e-8:
    errors.append(f"tip rotation differs by {dr:.3g}")
if dd > 1e-9:
    errors.append(f"tendon displacements differ by {dd:.3g} m")
if errors:
    sys.exit(f"{scene}: " + "; ".join(errors))
print(f"{scene}: {answer['model']} {answer['status']}, tip within {dp:.2g} m of the expected answer")
