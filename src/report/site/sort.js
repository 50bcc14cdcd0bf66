// Sorting of the report's points table (report::site::points_table): a click on a header sorts
// by its column (again: the other way); the address says how it is sorted (`#sort=KEY`,
// `#sort=-KEY` descending), so a sorted table can be linked and reopened. Cells sort by their
// `data-v` (numbers numerically), empty ones last; equal ones keep the point order. Without
// this script the table stays in point order.
(function () {
  "use strict";
  var table = document.getElementById("points-table");
  if (!table) { return; }
  document.documentElement.classList.add("js");
  var body = table.tBodies[0];
  var heads = table.tHead.rows[0].cells;
  var original = Array.prototype.slice.call(body.rows);
  function column(key) {
    for (var i = 0; i < heads.length; i++) {
      if (heads[i].getAttribute("data-key") === key) { return i; }
    }
    return -1;
  }
  function value(row, k) {
    var v = row.cells[k].getAttribute("data-v");
    if (v === null || v === "") { return null; }
    var x = Number(v);
    return isNaN(x) ? v : x;
  }
  function sort(spec) {
    var desc = spec.charAt(0) === "-";
    var key = desc ? spec.slice(1) : spec;
    var k = column(key);
    if (k < 0) { return; }
    var rows = original.slice();
    rows.sort(function (a, b) {
      var x = value(a, k), y = value(b, k);
      if (x === null || y === null) { return (x === null) - (y === null); }
      var c = (typeof x === "number" && typeof y === "number")
        ? x - y : String(x).localeCompare(String(y));
      return desc ? -c : c;
    });
    rows.forEach(function (r) { body.appendChild(r); });
    for (var i = 0; i < heads.length; i++) {
      heads[i].setAttribute("aria-sort", i === k ? (desc ? "descending" : "ascending") : "none");
    }
  }
  function current() {
    var m = /^#sort=(.+)$/.exec(window.location.hash);
    return m ? decodeURIComponent(m[1]) : null;
  }
  Array.prototype.forEach.call(heads, function (th) {
    var key = th.getAttribute("data-key");
    if (!key) { return; }
    th.tabIndex = 0;
    function go() {
      var spec = current() === key ? "-" + key : key;
      try {
        window.history.replaceState(null, "", "#sort=" + encodeURIComponent(spec));
      } catch (e) { /* a file:// page may refuse: the sort still applies */ }
      sort(spec);
    }
    th.addEventListener("click", go);
    th.addEventListener("keydown", function (e) { if (e.key === "Enter") { go(); } });
  });
  window.addEventListener("hashchange", function () { var s = current(); if (s) { sort(s); } });
  var s = current();
  if (s) { sort(s); }
})();
