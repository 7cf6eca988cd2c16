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

// u = s (u - tau r [+ kd]) (kd may be null), then ContactGapSum of the new u.
double UpdateAndSum(size_t B, double s, double tau, const double* r, const double* kd,
                    const double* g0, const double* p, double* u, size_t* nc);

// The working set of a bx x by box: g = g0 + u - gbar where g0 is finite
// (0 elsewhere); S = cells with p > 0 or finite g0 and g < 0, in box order;
// gS, pS: g and p on S. The preconditioner's input, g on S and 0 elsewhere,
// goes to row j + hw, column hw of the padded array (row length px): into
// gp (double) or, if gp is null, into gpf (float). S, gS, pS hold B
// entries. Returns |S|.
size_t BuildSet(int bx, int by, int px, int hw, const double* g0, const double* u,
                const double* p, double gbar, double* gp, float* gpf, int* S, double* gS,
                double* pS);

// xS[k] = x[S[k]]; returns their sum.
double GatherSum(size_t ns, const int* S, const double* x, double* xS);
// xS[k] = x[S[k]].
void Gather(size_t ns, const int* S, const double* x, double* xS);
// sum of x[S[k]] * yS[k].
double GatherDot(size_t ns, const int* S, const double* x, const double* yS);
// xS -= mean; returns the sum of gS * xS.
double CenterDot(size_t ns, double mean, double* xS, const double* gS);
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
