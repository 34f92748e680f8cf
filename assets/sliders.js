// The design sliders' tooltip (dcc.Slider tooltip.transform): the value without float noise (a
// slider computes min + k * step: 0.07780000000000001 shows as 0.0778).
window.dccFunctions = window.dccFunctions || {};
window.dccFunctions.shimmyOnStep = function (value) {
    return typeof value === "number" && isFinite(value) ? String(Number(value.toPrecision(12))) : value;
};
