// Real roots of polynomials of degree 1 to 4 in double precision. MBOIT needs the real
// roots of the kernel polynomial of degree N/2 (Münstermann et al. 2018, I3D, Sec. 3); for
// a positive definite Hankel matrix all of them are real and distinct, so these solvers
// treat a slightly negative discriminant (rounding) as zero rather than dropping roots.
#ifndef apcPolynomialRoots_h
#define apcPolynomialRoots_h

namespace apc
{

// Each solver takes the coefficients c[0] + c[1] x + ... (lowest degree first), writes the
// real roots in ascending order (double roots repeated) and returns how many it found.
// A vanishing leading coefficient drops to the next lower degree. Roots from the closed
// forms are polished by Newton steps on the original polynomial, because the closed forms
// lose digits through cancellation when roots are clustered or large.
int SolveQuadratic(const double c[3], double roots[2]);
int SolveCubic(const double c[4], double roots[3]);
int SolveQuartic(const double c[5], double roots[4]);

// c[0] + c[1] x + ... + c[degree] x^degree by Horner's rule.
double EvaluatePolynomial(const double* c, int degree, double x);

} // namespace apc

#endif
