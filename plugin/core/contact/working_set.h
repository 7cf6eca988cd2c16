// The preconditioned CG's (contact_solver.cc) passes over its working set S
// and over the solve box, in four double lanes (AVX2 clones, common/simd.h).
//
// Every sum runs in the order of the solver's Sum4: term k in partial sum
// k mod 4 over the full blocks of four, the tail into the first, combined
// as (s0 + s1) + (s2 + s3). Four lanes over contiguous k are those partial
// sums, so these passes give the scalar ones' bits (no FMA contraction:
// -ffp-contract=off). The working set's values live in contiguous arrays
// (index k of S), gathered from the box once per iteration.
#ifndef MJTOUCH_CONTACT_WORKING_SET_H_
#define MJTOUCH_CONTACT_WORKING_SET_H_

#include <cstddef>

namespace mjtouch {
namespace working_set {

// sum over the contact (p > 0) of g0 + u; its size in *nc.
double ContactGapSum(size_t B, const double* g0, const double* u, const double* p, size_t* nc);

// p *= scale, u = scale u_from (u_from may be u), then ContactGapSum.
double ScaleStart(size_t B, double scale, double* p, const double* u_from, double* u,
                  const double* g0, size_t* nc);

// u = s (u - tau r [+ kd]) (kd may be null), then ContactGapSum of the new u.
double UpdateAndSum(size_t B, double s, double tau, const double* r, const double* kd,
                    const double* g0, const double* p, double* u, size_t* nc);

// The working set of a bx x by box: g = g0 + u - gbar; S = cells with p > 0
// or g < 0, in box order (g0 = +inf off the candidates, as LoadGuess
// leaves it, and p = 0 there: they stay out);
// gS, pS: g and p on S; oS: t on S (read_t; else 0), t then zeroed on the
// box. The preconditioner's input, g on S and 0 elsewhere with a zero
// border of hw, fills the padded array (row length px, by + 2 hw rows): gp
// (double) or, if gp is null, gpf (float). S, gS, pS, oS hold B entries
// (written four lanes at a time, never past the cell being read).
// row_first (by + 1 entries): row j's cells are S[row_first[j] ..
// row_first[j + 1]). Returns |S|.
size_t BuildSet(int bx, int by, int px, int hw, const double* g0, const double* u, const double* p,
                double gbar, double* gp, float* gpf, double* t, bool read_t, int* S, double* gS,
                double* pS, double* oS, size_t* row_first);

// The solve's start from a bx x by window of the grid (rows `stride`
// apart): g0 = gap on candidates (finite gap), +inf elsewhere (one
// comparison then tells the cells that may touch); p = max(0, given) on
// candidates, 0 where not a candidate or not finite; the cells whose p
// differs from given go to changed (box order, count in *nchanged; B
// entries). Returns sum(p) in box order; the candidates' count in *ncand.
double LoadGuess(int bx, int by, size_t stride, const double* gap, const double* given, double* g0,
                 double* p, size_t* ncand, int* changed, size_t* nchanged);

// In box order over the contact (p > 0): the sum of g0 + u, the largest g0
// (-inf if none) in *max_g0 and the count in *nc.
double ContactSummary(size_t B, const double* g0, const double* u, const double* p, size_t* nc,
                      double* max_g0);

// xS[k] = x[S[k]]; returns their sum.
double GatherSum(size_t ns, const int* S, const double* x, double* xS);
// sum of x[S[k]] * yS[k].
double GatherDot(size_t ns, const int* S, const double* x, const double* yS);
// xS -= mean (and x_box[S[k]] = xS[k] if x_box is not null); returns the
// sum of gS * xS.
double CenterDot(size_t ns, double mean, double* xS, const double* gS, const int* S = nullptr,
                 double* x_box = nullptr);
// tS = zS + beta oS; returns the sum of tS.
double AxpySum(size_t ns, double beta, const double* zS, const double* oS, double* tS);

// The step projected onto p >= 0: v = pS - tau tS, pnS = v < 0 ? 0 : v;
// where v < 0, delta[S[k]] = -v and S[k] goes to changed (in k order, their
// count in *nchg; changed holds ns entries). Returns the sum of pnS.
double StepProject(size_t ns, double tau, const double* pS, const double* tS, const int* S,
                   double* pnS, double* delta, int* changed, size_t* nchg);

// v = s pnS; returns the sum of |v - pS|, and writes p[S[k]] = v.
double ScaleChange(size_t ns, double s, const double* pnS, const double* pS, const int* S,
                   double* p);

}  // namespace working_set
}  // namespace mjtouch

#endif  // MJTOUCH_CONTACT_WORKING_SET_H_
