"""What skins cost on a whole robot hand (mjtouch.bench.hand): the Shadow
hand of Gymnasium-Robotics at its 2 ms step, five fingertip skins; the same
as ``python -m mjtouch bench --hand``.

    python examples/bench_hand.py [--steps N] [--repeats R] [--threads T] [--quick]
"""

from mjtouch.bench.hand import main

if __name__ == "__main__":
    raise SystemExit(main())
