import sys, json, time
from pathlib import Path
from hydra import compose, initialize_config_dir
from benchmark.core.config_files import CONFIG_DIR
from benchmark.analysis.blind import BlindSettings, make_set
from benchmark.analysis.blind_sources import SOURCES
from benchmark import api
source, seed, idx = sys.argv[1], int(sys.argv[2]), [int(x) for x in sys.argv[3].split(",")]
work = Path(f"outputs/{source}_{seed}")
with initialize_config_dir(config_dir=str(CONFIG_DIR), version_base=None):
    cfg = compose("blind", overrides=[f"source={source}", "forms=heldout", "n=20", f"seed={seed}", f"workdir={work.parent}/w"])
st = BlindSettings.from_run(cfg)
draws, make = SOURCES[source](st)
for i in idx:
    d = draws[i]
    folder = make_set(d, make, work)
    t0 = time.time()
    doc = api.diagnose(folder, outdir=work / "diag" / folder.name, seed=seed, figures=False)
    print(i, d["effects"], "->", getattr(doc, "status", None) or doc.get("status") if isinstance(doc, dict) else doc, f"{time.time()-t0:.0f} s", flush=True)
