// A compass (pattern) search for a few smooth-enough parameters with a costly, noise-free
// cost (e.g. a likelihood under common random numbers): no gradients, no line search.
//
// From `v`, over its coordinates [first, last) (or its first `coordinates`): each up and
// down by the step, on along a direction while it pays (up to four steps); the step
// halves when a whole sweep finds nothing better, from ln 2 down to ln 1.05 (the
// coordinates are logarithms: factors of 2 down to 5 %), or until *evaluations reaches
// `budget`. `clamp` keeps a trial within bounds. *best holds cost(v) on entry and the
// best found on return. A trial at a point already evaluated in this search (a poll back
// to where a move came from) takes the cost found there: it counts as an evaluation, so
// the path and the result are the same, but the cost is not computed again (a seventh of
// identify's noise searches on a minute of log).
//
// With `min_gain` > 0 a trial moves the search only where it lowers the cost by more
// than that (a sufficient decrease): a cost that is a mean over N rows of a log density
// tells little apart below a tenth of a nat in all, so min_gain = 0.1 / N spares the
// search the polls that polish digits the rows cannot tell apart. Too coarse a gain
// stops it early along a ridge it would climb in small steps.
//
//   double best = cost(start);
//   int evaluations = 1;
//   auto v = PatternSearch<Values>(cost, clamp, start, 4, 80, &best, &evaluations);
#pragma once

#include <cmath>
#include <functional>
#include <map>

namespace twinsim {

template <class V>
V PatternSearch(const std::function<double(const V&)>& cost, const std::function<V(V)>& clamp, V v, int first, int last,
                int budget, double* best, int* evaluations, double min_gain = 0) {
  // Every trial's cost, by its exact coordinates: a poll back to a point already
  // evaluated (the one a move came from) counts as an evaluation, as it always has, but
  // is not computed again.
  std::map<V, double> seen;
  seen.emplace(v, *best);
  for (double step = std::log(2.0); step >= std::log(1.05) && *evaluations < budget; step /= 2) {
    bool moved = true;
    while (moved && *evaluations < budget) {
      moved = false;
      for (int i = first; i < last && *evaluations < budget; ++i) {
        for (double sign : {1.0, -1.0}) {
          bool paid = false;
          for (int k = 0; k < 4 && *evaluations < budget; ++k) {
            V trial = v;
            trial[i] += sign * step;
            trial = clamp(trial);
            if (trial[i] == v[i]) break;
            const auto known = seen.find(trial);
            const double c = known != seen.end() ? known->second : cost(trial);
            if (known == seen.end()) seen.emplace(trial, c);
            ++*evaluations;
            if (c >= *best - min_gain) break;
            *best = c, v = trial, moved = paid = true;
          }
          if (paid) break;
        }
      }
    }
  }
  return v;
}

template <class V>
V PatternSearch(const std::function<double(const V&)>& cost, const std::function<V(V)>& clamp, V v, int coordinates,
                int budget, double* best, int* evaluations, double min_gain = 0) {
  return PatternSearch<V>(cost, clamp, v, 0, coordinates, budget, best, evaluations, min_gain);
}

}  // namespace twinsim
