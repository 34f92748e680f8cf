// How the last design change was made, for the pages that follow the design once it stands still
// (ui/live.py): the pointer is down (a slider being dragged), was released, or a key was pressed (a
// slider moved by the arrow keys, which the user may press again). Functions waiting for the release
// are called on it (a release outside the window counts: the window loses the pointer).
(function () {
    const input = window.shimmyInput = window.shimmyInput || {pointerDown: false, last: null, onRelease: []};
    document.addEventListener("pointerdown", function () { input.pointerDown = true; input.last = "pointer"; }, true);
    const released = function () {
        input.pointerDown = false;
        input.onRelease.splice(0).forEach(function (f) { f(); });
    };
    document.addEventListener("pointerup", released, true);
    document.addEventListener("pointercancel", released, true);
    window.addEventListener("blur", released);
    document.addEventListener("keydown", function () { input.last = "key"; }, true);
})();
