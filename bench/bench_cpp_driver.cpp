// bench_cpp's driver: the equations tool's C of an arm against Pinocchio's CppADCodeGen
// kernels of the same arm (CodeGenRNEA, CodeGenCRBA, CodeGenRNEADerivatives, CodeGenABA,
// CodeGenABADerivatives, CodeGenMinv), timed in alternating blocks over the same random
// states. Both are C compiled by the same gcc with the same flags into shared libraries and
// called through a function pointer: ours (arm_eom.c) by bench_cpp.py, CodeGen's here at
// run time. Compiled once for every arm: the arm is read from a file (see read_model).
//
//   driver <model file> <arm library> <gcc> <flags> <seconds per block> <blocks>
//
// prints "state <q> <qd> <qdd> <tau>" per joint and "x <quantity> <index> <ours> <CodeGen's>"
// for state 0 (the check), then "time <quantity> <ours s/call> <CodeGen's s/call>" per
// quantity and block.
#include <pinocchio/codegen/cppadcg-algo.hpp>

#include <dlfcn.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

typedef CppAD::cg::ArrayView<const double> In;
typedef CppAD::cg::ArrayView<double> Out;

// The arm: a line "gravity gx gy gz", then one line per joint: "parent kind ax ay az
// R(9, row by row) p(3) mass c(3) I(9) armature", kind one of RX RY RZ PX PY PZ RU PU
// (U: about the axis a), R and p its placement in its parent, the body at the joint.
static pinocchio::Model read_model(const char *path)
{
    std::ifstream in(path);
    std::string word;
    pinocchio::Model model;
    in >> word >> model.gravity.linear()[0] >> model.gravity.linear()[1] >> model.gravity.linear()[2];
    std::vector<double> armature;
    int parent;
    while (in >> parent >> word) {
        double v[29];
        for (double &x : v) in >> x;
        Eigen::Vector3d axis(v[0], v[1], v[2]), p(v[12], v[13], v[14]), c(v[16], v[17], v[18]);
        Eigen::Matrix3d R, I;
        R << v[3], v[4], v[5], v[6], v[7], v[8], v[9], v[10], v[11];
        I << v[19], v[20], v[21], v[22], v[23], v[24], v[25], v[26], v[27];
        pinocchio::SE3 placement(R, p);
        pinocchio::JointIndex id;
        const std::string name = "j" + std::to_string(model.njoints);
        if (word == "RX") id = model.addJoint(parent, pinocchio::JointModelRX(), placement, name);
        else if (word == "RY") id = model.addJoint(parent, pinocchio::JointModelRY(), placement, name);
        else if (word == "RZ") id = model.addJoint(parent, pinocchio::JointModelRZ(), placement, name);
        else if (word == "PX") id = model.addJoint(parent, pinocchio::JointModelPX(), placement, name);
        else if (word == "PY") id = model.addJoint(parent, pinocchio::JointModelPY(), placement, name);
        else if (word == "PZ") id = model.addJoint(parent, pinocchio::JointModelPZ(), placement, name);
        else if (word == "RU") id = model.addJoint(parent, pinocchio::JointModelRevoluteUnaligned(axis), placement, name);
        else if (word == "PU") id = model.addJoint(parent, pinocchio::JointModelPrismaticUnaligned(axis), placement, name);
        else {
            fprintf(stderr, "unknown joint kind %s\n", word.c_str());
            exit(2);
        }
        model.appendBodyToJoint(id, pinocchio::Inertia(v[15], c, I), pinocchio::SE3::Identity());
        armature.push_back(v[28]);
    }
    for (size_t i = 0; i < armature.size(); ++i) model.armature[i] = armature[i];
    model.name = "arm";
    return model;
}

// the equations tool's functions, from the arm's library
typedef void (*Fn3)(const double *, const double *, const double *, double *);
typedef void (*Fn3x2)(const double *, const double *, const double *, double *, double *);
typedef void (*Fn1)(const double *, double *);
template <class F> static F symbol(void *library, const char *name)
{
    void *f = dlsym(library, name);
    if (f == nullptr) {
        fprintf(stderr, "no %s in the arm's library\n", name);
        exit(2);
    }
    return reinterpret_cast<F>(f);
}

// A CodeGen kernel of Pinocchio with its compiled function at hand (ForwardZero only).
template <class G> struct Opened : G {
    explicit Opened(const pinocchio::Model &model) : G(model) { this->build_jacobian = false; }
    CppAD::cg::GenericModel<double> &function() { return *this->generatedFun_ptr; }
    void save_sources(const std::string &folder)
    {
        CppAD::cg::SaveFilesModelLibraryProcessor<double>(*this->libcgen_ptr).saveSourcesTo(folder + "/" + this->function_name);
    }
};

template <class G>
static std::unique_ptr<Opened<G>> built(const pinocchio::Model &model, const std::string &gcc, const std::string &flags)
{
    std::unique_ptr<Opened<G>> g(new Opened<G>(model));
    g->initLib();
    g->compileLib(gcc, flags);
    g->loadLib(false);
    if (const char *folder = getenv("BENCH_CPP_SOURCES")) g->save_sources(folder);  // to read them
    return g;
}

static const int STATES = 1024;  // the loops cycle through these (no folding of one state)

struct Pair {
    const char *name;
    std::function<void(int)> ours, codegen;
    long calls;
};

static double block(long calls, const std::function<void(int)> &f)
{
    auto t0 = std::chrono::steady_clock::now();
    for (long k = 0; k < calls; ++k) f((int)(k % STATES));
    auto t1 = std::chrono::steady_clock::now();
    return std::chrono::duration<double>(t1 - t0).count() / calls;
}

int main(int argc, char **argv)
{
    if (argc != 7) {
        fprintf(stderr, "usage: driver <model file> <arm library> <gcc> <flags> <seconds per block> <blocks>\n");
        return 2;
    }
    const pinocchio::Model model = read_model(argv[1]);
    void *library = dlopen(argv[2], RTLD_NOW | RTLD_LOCAL);
    if (library == nullptr) {
        fprintf(stderr, "%s\n", dlerror());
        return 2;
    }
    const std::string gcc = argv[3], flags = argv[4];
    const double seconds = atof(argv[5]);
    const int blocks = atoi(argv[6]);
    const int N = model.nv, T = N * (N + 1) / 2;  // T: CRBA's and Minv's outputs, the upper triangle
    const Fn3 arm_tau = symbol<Fn3>(library, "arm_tau"), arm_qdd = symbol<Fn3>(library, "arm_qdd");
    const Fn3x2 arm_dtau = symbol<Fn3x2>(library, "arm_dtau"), arm_dqdd = symbol<Fn3x2>(library, "arm_dqdd");
    const Fn1 arm_M = symbol<Fn1>(library, "arm_M"), arm_Minv = symbol<Fn1>(library, "arm_Minv");

    auto rnea = built<pinocchio::CodeGenRNEA<double>>(model, gcc, flags);
    auto crba = built<pinocchio::CodeGenCRBA<double>>(model, gcc, flags);
    auto rnea_d = built<pinocchio::CodeGenRNEADerivatives<double>>(model, gcc, flags);
    auto aba = built<pinocchio::CodeGenABA<double>>(model, gcc, flags);
    auto aba_d = built<pinocchio::CodeGenABADerivatives<double>>(model, gcc, flags);
    auto minv = built<pinocchio::CodeGenMinv<double>>(model, gcc, flags);

    // per state, q, qd, qdd and tau apart for ours; [q, qd, qdd] and [q, qd, tau] for CodeGen
    std::vector<double> states(STATES * 10 * N);
    unsigned s = 12345u;
    auto uniform = [&](double low, double high) {
        s = s * 1103515245u + 12345u;
        return low + (double)(s >> 8) / 16777216.0 * (high - low);
    };
    auto q = [&](int i) { return &states[i * 10 * N]; };
    auto qd = [&](int i) { return &states[i * 10 * N + N]; };
    auto qdd = [&](int i) { return &states[i * 10 * N + 2 * N]; };
    auto tau = [&](int i) { return &states[i * 10 * N + 3 * N]; };
    auto x = [&](int i) { return &states[i * 10 * N + 4 * N]; };
    auto xt = [&](int i) { return &states[i * 10 * N + 7 * N]; };
    for (int i = 0; i < STATES; ++i) {
        for (int j = 0; j < N; ++j) {
            q(i)[j] = uniform(-3.0, 3.0), qd(i)[j] = uniform(-2.0, 2.0), qdd(i)[j] = uniform(-5.0, 5.0);
            tau(i)[j] = uniform(-20.0, 20.0);
        }
        std::copy(q(i), q(i) + 3 * N, x(i));  // q, qd, qdd
        std::copy(q(i), q(i) + 2 * N, xt(i)), std::copy(tau(i), tau(i) + N, xt(i) + 2 * N);
    }
    std::vector<double> ours_out(3 * N * N), cg_out(3 * N * N), triangle(N * N);
    double *a = ours_out.data(), *b = cg_out.data(), *t = triangle.data();
    double sum = 0.0;

    /* the check: both results for state 0, and the state itself */
    for (int j = 0; j < N; ++j) printf("state %.17g %.17g %.17g %.17g\n", q(0)[j], qd(0)[j], qdd(0)[j], tau(0)[j]);
    auto show = [](const char *what, int count, const double *ours, const double *theirs) {
        for (int j = 0; j < count; ++j) printf("x %s %d %.17g %.17g\n", what, j, ours[j], theirs[j]);
    };
    auto upper = [&](const double *full, double *out) {  // ours n x n -> CodeGen's layout
        int k = 0;
        for (int i = 0; i < N; ++i)
            for (int j = i; j < N; ++j) out[k++] = full[i * N + j];
    };
    auto &f_rnea = rnea->function(), &f_crba = crba->function(), &f_rnea_d = rnea_d->function();
    auto &f_aba = aba->function(), &f_aba_d = aba_d->function(), &f_minv = minv->function();
    arm_tau(q(0), qd(0), qdd(0), a), f_rnea.ForwardZero(In(x(0), 3 * N), Out(b, N)), show("tau", N, a, b);
    arm_M(q(0), a), upper(a, t), f_crba.ForwardZero(In(q(0), N), Out(b, T)), show("M", T, t, b);
    arm_dtau(q(0), qd(0), qdd(0), a, a + N * N);
    f_rnea_d.ForwardZero(In(x(0), 3 * N), Out(b, 3 * N * N)), show("dtau", 2 * N * N, a, b);
    arm_qdd(q(0), qd(0), tau(0), a), f_aba.ForwardZero(In(xt(0), 3 * N), Out(b, N)), show("qdd", N, a, b);
    arm_dqdd(q(0), qd(0), tau(0), a, a + N * N);
    f_aba_d.ForwardZero(In(xt(0), 3 * N), Out(b, 3 * N * N)), show("dqdd", 2 * N * N, a, b);
    arm_Minv(q(0), a), upper(a, t), f_minv.ForwardZero(In(q(0), N), Out(b, T)), show("Minv", T, t, b);

    const int NN = N * N;
    std::vector<Pair> pairs = {
        {"tau", [&](int i) { arm_tau(q(i), qd(i), qdd(i), a); sum += a[i % N]; },
         [&](int i) { f_rnea.ForwardZero(In(x(i), 3 * N), Out(b, N)); sum += b[i % N]; }, 0},
        {"M", [&](int i) { arm_M(q(i), a); sum += a[i % NN]; },
         [&](int i) { f_crba.ForwardZero(In(q(i), N), Out(b, T)); sum += b[i % T]; }, 0},
        {"dtau", [&](int i) { arm_dtau(q(i), qd(i), qdd(i), a, a + NN); sum += a[i % (2 * NN)]; },
         [&](int i) { f_rnea_d.ForwardZero(In(x(i), 3 * N), Out(b, 3 * NN)); sum += b[i % (2 * NN)]; }, 0},
        {"qdd", [&](int i) { arm_qdd(q(i), qd(i), tau(i), a); sum += a[i % N]; },
         [&](int i) { f_aba.ForwardZero(In(xt(i), 3 * N), Out(b, N)); sum += b[i % N]; }, 0},
        {"dqdd", [&](int i) { arm_dqdd(q(i), qd(i), tau(i), a, a + NN); sum += a[i % (2 * NN)]; },
         [&](int i) { f_aba_d.ForwardZero(In(xt(i), 3 * N), Out(b, 3 * NN)); sum += b[i % (2 * NN)]; }, 0},
        {"Minv", [&](int i) { arm_Minv(q(i), a); sum += a[i % NN]; },
         [&](int i) { f_minv.ForwardZero(In(q(i), N), Out(b, T)); sum += b[i % T]; }, 0},
    };
    for (auto &p : pairs) {  // calls per block: about `seconds` of the slower of the two
        block(STATES, p.ours), block(STATES, p.codegen);
        double slower = std::max(block(4 * STATES, p.ours), block(4 * STATES, p.codegen));
        p.calls = std::max(1L, (long)(seconds / slower));
    }
    for (int k = 0; k < blocks; ++k)
        for (auto &p : pairs) {  // the two in turn, which first alternating from block to block
            double ours, theirs;
            if (k % 2 == 0) ours = block(p.calls, p.ours), theirs = block(p.calls, p.codegen);
            else theirs = block(p.calls, p.codegen), ours = block(p.calls, p.ours);
            printf("time %s %.12e %.12e\n", p.name, ours, theirs);
        }
    fprintf(stderr, "%g\n", sum);
    dlclose(library);
    return 0;
}
