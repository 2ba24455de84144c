#!/usr/bin/env python3
"""The models layer's dependencies point one way (docs/design-notes.md, "The layers"):
services (and dynamics) -> models (cc, ccsub, prb, vc, vcref, lumped) -> solve -> physics -> bvp, core.
Reads every #include "..." under models/ and bvp/ and fails, naming the file and the include,
where a file reaches a layer above its own or a sibling model's folder."""
import pathlib
import re
import sys

root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".")
RANK = {"core": 0, "bvp": 1, "physics": 2, "solve": 3, "model": 4, "services": 5}
MODEL_FOLDERS = {"cc", "ccsub", "prb", "vc", "vcref", "lumped"}
# Public headers of tdcr/models/, by the layer they belong to.
PUBLIC = {
    "cosserat_rod.hpp": "physics", "tendon_physics.hpp": "physics",
    "static_model.hpp": "solve", "model_problem.hpp": "solve", "dynamics.hpp": "solve",
    "answer_linearisation.hpp": "solve",
    "cc.hpp": "cc", "ccsub.hpp": "ccsub", "prb.hpp": "prb", "vc.hpp": "vc", "vcref.hpp": "vcref",
    "lumped_model.hpp": "lumped",
    # The integrator interface, implemented by the models (like static_model.hpp).
    "dynamics.hpp": "solve",
}


def layer_of_folder(folder):
    if folder in MODEL_FOLDERS:
        return "model"
    if folder == "dynamics":  # simulate and the integrators' dispatch: a service
        return "services"
    return folder


def where(include, including_file):
    """(layer, folder) of an include path, or None for system and third-party headers."""
    parts = include.split("/")
    if parts[0] == "tdcr" and len(parts) >= 3:
        if parts[1] in ("core", "bvp"):
            return parts[1], parts[1]
        if parts[1] == "models":
            folder = PUBLIC.get(parts[2], "services")
            return layer_of_folder(folder), folder
        return None
    if parts[0] in MODEL_FOLDERS | {"physics", "solve", "services", "dynamics"}:
        return layer_of_folder(parts[0]), parts[0]
    if len(parts) == 1:  # same folder: the including file's own layer
        return own_layer(including_file)
    return None


def own_layer(path):
    rel = path.relative_to(root).parts
    if rel[0] == "bvp":
        return "bvp", "bvp"
    if rel[0] == "models" and rel[1] == "include":
        folder = PUBLIC.get(rel[-1], "services")
        return layer_of_folder(folder), folder
    if rel[0] == "models":
        return layer_of_folder(rel[1]), rel[1]
    return None


bad = []
files = [p for d in ("models", "bvp") for p in (root / d).rglob("*") if p.suffix in (".cpp", ".hpp")]
for f in files:
    mine = own_layer(f)
    if mine is None:
        continue
    for line_no, line in enumerate(f.read_text().splitlines(), 1):
        m = re.match(r'\s*#\s*include\s+"([^"]+)"', line)
        if not m:
            continue
        target = where(m.group(1), f)
        if target is None:
            continue
        (layer, folder), (tlayer, tfolder) = mine, target
        up = RANK[tlayer] > RANK[layer]
        # A model may use the lumped base; no model uses another model's folder.
        sibling = layer == "model" and tlayer == "model" and tfolder != folder and tfolder != "lumped"
        if up or sibling:
            bad.append(f"{f.relative_to(root)}:{line_no}: {layer} ({folder}) includes {m.group(1)} ({tlayer})")
for b in bad:
    print(b)
print(f"{len(files)} files checked, {len(bad)} includes against the layers")
sys.exit(1 if bad else 0)
