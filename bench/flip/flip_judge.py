"""FLIP (Andersson et al. 2020, NVIDIA's flip-evaluator package) as a judge for
`fsot eval --flip`: reads sequences on stdin, answers each with its mean FLIP.

Protocol, repeated until stdin closes: a line "WIDTH HEIGHT FRAMES PPD", then
WIDTH x HEIGHT x FRAMES little-endian float32 values of the test frames, then
as many of the reference frames, both display-encoded sRGB grey in [0, 1].
The answer is one line: the mean over frames of each frame's mean FLIP error
(LDR, grey as three equal sRGB channels, at PPD pixels per degree).
"""
import sys

import numpy as np
import flip_evaluator as flip


def main():
    stdin, stdout = sys.stdin.buffer, sys.stdout
    while True:
        header = stdin.readline()
        if not header:
            return
        w, h, frames, ppd = header.split()
        w, h, frames, ppd = int(w), int(h), int(frames), float(ppd)
        count = w * h * frames
        data = stdin.read(8 * count)
        if len(data) != 8 * count:
            raise SystemExit("flip_judge: the input ended inside a sequence")
        values = np.frombuffer(data, dtype="<f4").reshape(2, frames, h, w)
        total = 0.0
        for f in range(frames):
            test = np.repeat(values[0, f][:, :, None], 3, axis=2).astype(np.float32)
            ref = np.repeat(values[1, f][:, :, None], 3, axis=2).astype(np.float32)
            _, mean, _ = flip.evaluate(ref, test, "LDR", inputsRGB=True, applyMagma=False,
                                       parameters={"ppd": ppd})
            total += float(mean)
        stdout.write(f"{total / frames:.9g}\n")
        stdout.flush()


if __name__ == "__main__":
    main()
