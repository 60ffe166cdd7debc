"""The GIL is released while rendering: another Python thread keeps running during a render
(checked by what it has done at each progress report, not by timing), and two Python threads
rendering at once both finish with the same images as one render alone."""

import threading

import inimtrace
from conftest import same_bits


def slow_setup():
    # The pure-Rust BVH on a 540 x 540 LA render: a few seconds on one thread.
    return inimtrace.Scene.paper(), inimtrace.Display.paper(set={"display.lcd.resolution": [540, 540]})


def test_another_python_thread_runs_while_a_render_runs():
    scene, display = slow_setup()
    counter = [0]
    seen = []  # the other thread's counter at each progress report
    done = threading.Event()

    def progress(stage, step, total):
        seen.append(counter[0])

    def render():
        try:
            inimtrace.render_display(scene, display, "LA", backend="bvh", threads=1, progress=progress)
        finally:
            done.set()

    worker = threading.Thread(target=render)
    worker.start()
    while not done.is_set():
        counter[0] += 1
    worker.join()
    # Reports come at least 0.1 s apart, each while the render is under way; between any two the
    # main thread counted on: it held the GIL while Rust rendered.
    assert len(seen) >= 3, seen
    assert all(b > a for a, b in zip(seen[:-2], seen[1:-1])), seen
    assert seen[-1] >= seen[-2]


def test_two_threads_rendering_at_once_both_finish_with_the_same_images():
    scene, display = inimtrace.Scene.paper(), inimtrace.Display.paper(set={"display.lcd.resolution": [540, 540]})
    alone = inimtrace.render_display(scene, display, "LA", threads=1)
    results = {}

    def render(key):
        results[key] = inimtrace.render_display(scene, display, "LA", threads=1)

    threads = [threading.Thread(target=render, args=(k,)) for k in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=120)
    assert sorted(results) == [0, 1]
    for img in results.values():
        assert same_bits(img, alone)
