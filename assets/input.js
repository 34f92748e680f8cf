// How the last design change was made, for the pages that follow the design once it stands still
// (ui/live.py): a pointer is down (a slider being dragged), all were released, or a key was pressed
// with no pointer down (a slider moved by the arrow keys, which the user may press again; a key
// pressed during a drag does not make it one). Functions waiting for the release are called when the
// last pointer down goes up (each pointer counted by its id) or the window loses them (blur).
(function () {
    const input = window.shimmyInput = window.shimmyInput ||
        {pointerDown: false, last: null, onRelease: [], pointers: new Set()};
    document.addEventListener("pointerdown", function (e) {
        input.pointers.add(e.pointerId);
        input.pointerDown = true;
        input.last = "pointer";
    }, true);
    const release = function () {
        input.pointerDown = false;
        input.onRelease.splice(0).forEach(function (f) { f(); });
    };
    const up = function (e) {
        input.pointers.delete(e.pointerId);
        if (input.pointers.size === 0) { release(); }
    };
    document.addEventListener("pointerup", up, true);
    document.addEventListener("pointercancel", up, true);
    window.addEventListener("blur", function () { input.pointers.clear(); release(); });
    document.addEventListener("keydown", function () { if (!input.pointerDown) { input.last = "key"; } }, true);
})();
