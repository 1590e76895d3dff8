/* C reference for the benchmark: the same exact zero-order-hold step of a 10-state, 5-input
   linear model as the FMU's doStep (x+ = Ad x + Bd u, row-major matrices), as a hand-written
   C FMU would do it after its argument checks. */
void reference_step(int nx, int nu, const double *ad, const double *bd, double *x, const double *u, double *scratch) {
    for (int i = 0; i < nx; i++) {
        double acc = 0.0;
        for (int j = 0; j < nx; j++) acc += ad[i * nx + j] * x[j];
        for (int j = 0; j < nu; j++) acc += bd[i * nu + j] * u[j];
        scratch[i] = acc;
    }
    for (int i = 0; i < nx; i++) x[i] = scratch[i];
}
