# Scores compensate's output against simulate's truth: awk -F, -f score.awk truth.csv out.csv
# Rows are matched by the `point` column (simulate's raw.csv carries it through compensate), or by their order
# where the output has none (a file that went through a format without carried columns, QIF). The error of a row
# is (compensated − true contact)·(actual outward normal), mm: the compensation error of DESIGN.md §3. Prints one
# line per status: count, mean, std and largest |error| in µm, and "all" over every computed row.
NR == FNR {
  if (FNR == 1) { for (c = 1; c <= NF; ++c) t[$c] = c; next }
  p = $(t["point"]); tx[p] = $(t["x"]); ty[p] = $(t["y"]); tz[p] = $(t["z"])
  tn1[p] = $(t["nx"]); tn2[p] = $(t["ny"]); tn3[p] = $(t["nz"]); next
}
FNR == 1 { for (c = 1; c <= NF; ++c) o[$c] = c; next }
{
  s = $(o["status"]); p = ("point" in o) ? $(o["point"]) : FNR - 1
  if ($(o["x"]) == "") { n[s] += 0; empty[s]++; next }
  e = ($(o["x"]) - tx[p]) * tn1[p] + ($(o["y"]) - ty[p]) * tn2[p] + ($(o["z"]) - tz[p]) * tn3[p]
  add(s, e); add("all", e)
}
function add(k, e) { n[k]++; sum[k] += e; sq[k] += e * e; a = e < 0 ? -e : e; if (a > mx[k]) mx[k] = a }
END {
  for (k in n) {
    if (n[k] == 0) { printf "%s: %d rows, none computed\n", k, empty[k]; continue }
    m = sum[k] / n[k]; v = n[k] > 1 ? (sq[k] - n[k] * m * m) / (n[k] - 1) : 0; if (v < 0) v = 0
    printf "%s: %d rows, mean %.2f std %.2f max %.2f um\n", k, n[k], 1000 * m, 1000 * sqrt(v), 1000 * mx[k]
  }
}
