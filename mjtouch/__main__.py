import pathlib
import sys

# `python -m mjtouch --include`: the directory of mjtouch.h, the C header of
# the plugin (for `gcc -I"$(python -m mjtouch --include)"`). Answered here,
# before the CLI, so it needs neither the plugin nor MuJoCo.
if sys.argv[1:] == ["--include"]:
    print(pathlib.Path(__file__).resolve().parent / "include")
    raise SystemExit(0)

from mjtouch.cli import main  # noqa: E402

raise SystemExit(main())
