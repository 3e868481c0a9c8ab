"""``map2map autocorrect``: turn SLAM maps into CAD-like plans with Model_BA."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ._mapargs import add_input_options, load_from_args


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "autocorrect",
        help="learned SLAM -> CAD auto-correct (Model_BA)",
        description="Auto-correct a SLAM map into a CAD-like plan (straight walls, no noise) "
        "with Model_BA, in the input's frame, resolution and origin. INPUT may be a folder: "
        "every map in it is corrected into the --out folder (same names).",
    )
    p.add_argument("input", metavar="INPUT", help="SLAM map (ROS yaml, PNG, ...) or a folder")
    p.add_argument("--out", required=True, help="output map (.yaml/.png/.pgm) or folder")
    p.add_argument("--model", default="pretrained",
                   help="'pretrained' (shipped weights), a training run folder or weights file")
    p.add_argument("--dxf", metavar="FILE", help="also write the walls as DXF line segments "
                   "(with a folder INPUT: a folder)")
    p.add_argument("--figure", metavar="PNG", help="before/after figure (folder INPUT: folder)")
    p.add_argument("--no-straighten", action="store_true",
                   help="only upsample and snap the output (no straight walls)")
    p.add_argument("--no-anchor", action="store_true",
                   help="place the walls where the network's low-resolution output says, "
                        "not on the input's observed wall faces (the default anchors them)")
    p.add_argument("--thickness", default=None, metavar="RULE",
                   help="thickness of the walls drawn behind a face seen from one side: "
                        "'shrink' (the training plans' walls scaled with the map's size), "
                        "'resolution' (their metres at the map's resolution), 'input' (from "
                        "the input's own walls) or a number of pixels (default: the "
                        "library's, learn.autocorrect.THICKNESS)")
    p.add_argument("--open-frontiers", action=argparse.BooleanOptionalAction, default=None,
                   help="leave out the network's walls at the edge of the known area or "
                        "beyond it (partial maps; default: learn.autocorrect.OPEN_FRONTIERS, "
                        "on for a map corrected in tiles)")
    p.add_argument("--large", choices=("resize", "tile", "refuse"), default=None,
                   help="maps more than 2.5x the training maps' size: resized whole, "
                        "corrected in overlapping tiles at the training scale, or returned "
                        "uncorrected (default: learn.autocorrect.LARGE)")
    p.add_argument("--device", default="cpu", help="torch device (default cpu)")
    add_input_options(p)
    p.set_defaults(func=run)


MAP_SUFFIXES = (".yaml", ".yml", ".png", ".pgm", ".jpg", ".jpeg", ".tif", ".tiff", ".json")


def run(args: argparse.Namespace) -> int:
    from ..core.errors import InputError
    from ..maps.formats import check_output_path, save_map

    try:
        from ..learn.ba.autocorrect import autocorrect_many, save_segments_dxf
        from ..learn.ba.model import load_model
        from ..learn.training.figures import save_before_after
    except ImportError as exc:
        raise InputError("autocorrect", f"needs PyTorch: pip install 'map2map[learn]' ({exc})"
                         ) from None
    src = Path(args.input)
    if src.is_dir():
        files = sorted(f for f in src.iterdir() if f.suffix.lower() in MAP_SUFFIXES)
        if not files:
            raise InputError(src, "no maps in this folder")
        out_dir = Path(args.out)
        outs = [out_dir / f.name for f in files]
        dxfs = [Path(args.dxf) / (f.stem + ".dxf") for f in files] if args.dxf else None
        figs = [Path(args.figure) / (f.stem + ".png") for f in files] if args.figure else None
    else:
        if not src.exists():
            raise InputError(src, "file not found")
        files, outs = [src], [Path(args.out)]
        dxfs = [Path(args.dxf)] if args.dxf else None
        figs = [Path(args.figure)] if args.figure else None
    for o in outs:
        check_output_path(o)
    maps = [load_from_args(argparse.Namespace(**{**vars(args), "input": f})) for f in files]
    model = load_model(args.model, args.device)
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        thickness = args.thickness
        if thickness is not None and thickness not in ("shrink", "resolution", "input"):
            try:
                thickness = float(thickness)
            except ValueError:
                raise InputError("--thickness", "'shrink', 'resolution', 'input' or a "
                                 f"number of pixels, not {thickness!r}") from None
        results = autocorrect_many(maps, model, straighten=not args.no_straighten,
                                   anchor=not args.no_anchor, device=args.device,
                                   thickness=thickness, open_frontiers=args.open_frontiers,
                                   large=args.large)
    for i, (f, r) in enumerate(zip(files, results, strict=True)):
        save_map(r.map, outs[i])
        if dxfs:
            save_segments_dxf(r.segments, dxfs[i])
        if figs:
            save_before_after(maps[i], r.map, figs[i], r.map.meta["autocorrect"]["segments_px"],
                              title=f"{f.name} -> {outs[i].name} ({Path(model.source).name})")
        for w in r.warnings:
            print(f"map2map: warning: {f}: {w}", file=sys.stderr)
    print(f"auto-corrected {len(results)} map(s) with {model.source}", file=sys.stderr)
    return 0
