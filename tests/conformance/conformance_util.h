// Helpers for the integrator conformance table: running the gradus binary as
// a child process (fork/exec, wall time, timeout, SIGINT), comparing and
// checking EXR outputs, and the two-sample statistics of the agreement test.
#pragma once
#include <gtest/gtest.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "image/image.h"

namespace gradus::conformance {

namespace fs = std::filesystem;

// ---------------------------------------------------------------- processes

struct ProcResult {
    bool exited = false;    // normal exit (WIFEXITED)
    int exitCode = -1;      // WEXITSTATUS when exited
    int signal = 0;         // terminating signal otherwise
    bool timedOut = false;  // killed by us after the timeout
    double seconds = 0;     // wall time from fork to reaping
    std::string out, err;
    std::string describe() const {
        std::ostringstream o;
        if (timedOut) o << "timed out after " << seconds << " s; ";
        if (exited) o << "exit " << exitCode;
        else o << "killed by signal " << signal;
        o << "; stderr: " << err;
        return o.str();
    }
};

inline std::string ReadText(const fs::path &p) {
    std::ifstream in(p);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

// A running gradus child: stdout/stderr go to files in `dir`.
class Child {
  public:
    Child(const std::vector<std::string> &args, const fs::path &dir) : dir_(dir) {
        static int counter = 0;
        const std::string tag = std::to_string(counter++);
        outFile_ = dir / ("stdout" + tag + ".txt");
        errFile_ = dir / ("stderr" + tag + ".txt");
        std::vector<std::string> all = {GRADUS_BIN};
        all.insert(all.end(), args.begin(), args.end());
        std::vector<char *> argv;
        for (auto &a : all) argv.push_back(a.data());
        argv.push_back(nullptr);
        start_ = std::chrono::steady_clock::now();
        pid_ = ::fork();
        if (pid_ == 0) {
            if (::chdir(dir.c_str()) != 0) ::_exit(126);
            int o = ::open(outFile_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
            int e = ::open(errFile_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
            if (o < 0 || e < 0) ::_exit(126);
            ::dup2(o, 1);
            ::dup2(e, 2);
            ::execv(argv[0], argv.data());
            ::_exit(127);
        }
    }
    Child(const Child &) = delete;
    Child &operator=(const Child &) = delete;
    ~Child() {
        if (pid_ > 0 && !reaped_) {
            ::kill(pid_, SIGKILL);
            ::waitpid(pid_, nullptr, 0);
        }
    }
    pid_t pid() const { return pid_; }
    double elapsed() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count(); }
    // Sends a signal to this child only.
    void signal(int sig) const {
        if (pid_ > 0 && !reaped_) ::kill(pid_, sig);
    }
    // Waits until the child exits; after `timeout` seconds it is killed (SIGKILL).
    ProcResult wait(double timeout) {
        ProcResult r;
        int st = 0;
        if (pid_ <= 0) return r;
        for (;;) {
            pid_t w = ::waitpid(pid_, &st, WNOHANG);
            if (w == pid_) break;
            if (elapsed() > timeout) {
                ::kill(pid_, SIGKILL);
                ::waitpid(pid_, &st, 0);
                r.timedOut = true;
                break;
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(2));
        }
        reaped_ = true;
        r.seconds = elapsed();
        r.exited = WIFEXITED(st);
        r.exitCode = r.exited ? WEXITSTATUS(st) : -1;
        r.signal = WIFSIGNALED(st) ? WTERMSIG(st) : 0;
        r.out = ReadText(outFile_);
        r.err = ReadText(errFile_);
        return r;
    }

  private:
    fs::path dir_, outFile_, errFile_;
    pid_t pid_ = -1;
    bool reaped_ = false;
    std::chrono::steady_clock::time_point start_;
};

inline ProcResult RunGradus(const std::vector<std::string> &args, const fs::path &dir, double timeout = 120) {
    Child c(args, dir);
    return c.wait(timeout);
}

// Names of the registered integrators: the first word of each line of
// `gradus --list-integrators`. Empty if the binary cannot be run.
inline std::vector<std::string> ListIntegrators() {
    fs::path dir = fs::temp_directory_path() / ("gradus_conformance_list_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    ProcResult r = RunGradus({"--list-integrators"}, dir, 60);
    fs::remove_all(dir);
    std::vector<std::string> names;
    if (!r.exited || r.exitCode != 0) return names;
    std::istringstream lines(r.out);
    std::string line;
    while (std::getline(lines, line)) {
        std::istringstream words(line);
        std::string first;
        if (words >> first) names.push_back(first);
    }
    return names;
}

// ---------------------------------------------------------------- images

// Every non-finite value, by channel; empty when all are finite.
inline std::string NonFiniteReport(const Image &img) {
    std::ostringstream o;
    const int nc = img.numChannels();
    for (int c = 0; c < nc; ++c) {
        long n = 0;
        for (int y = 0; y < img.height(); ++y)
            for (int x = 0; x < img.width(); ++x)
                if (!std::isfinite(img.at(x, y, c))) ++n;
        if (n) o << img.channelNames()[c] << ": " << n << " non-finite; ";
    }
    return o.str();
}

// Check 5 on one output: every channel of every layer finite, and the
// nonfinite_discarded count present (a non-negative integer). Returns it (-1 if absent).
inline long long CheckFiniteAndReported(const Image &img, const std::string &what) {
    EXPECT_EQ(NonFiniteReport(img), "") << what;
    auto it = img.metadata.find("nonfinite_discarded");
    if (it == img.metadata.end()) {
        ADD_FAILURE() << what << ": no nonfinite_discarded metadata";
        return -1;
    }
    char *end = nullptr;
    long long v = std::strtoll(it->second.c_str(), &end, 10);
    EXPECT_TRUE(!it->second.empty() && *end == 0 && v >= 0)
        << what << ": nonfinite_discarded = \"" << it->second << "\"";
    return v;
}

// Pixel data of every channel bit for bit (metadata ignored); "" when identical.
inline std::string BitwiseDifference(const Image &a, const Image &b) {
    std::ostringstream o;
    if (a.width() != b.width() || a.height() != b.height())
        return "size " + std::to_string(a.width()) + "x" + std::to_string(a.height()) + " vs " +
               std::to_string(b.width()) + "x" + std::to_string(b.height());
    if (a.channelNames() != b.channelNames()) return "different channel lists";
    const int nc = a.numChannels();
    for (int c = 0; c < nc; ++c) {
        long n = 0;
        int fx = -1, fy = -1;
        float va = 0, vb = 0;
        for (int y = 0; y < a.height(); ++y)
            for (int x = 0; x < a.width(); ++x) {
                float p = a.at(x, y, c), q = b.at(x, y, c);
                uint32_t bp, bq;
                std::memcpy(&bp, &p, 4);
                std::memcpy(&bq, &q, 4);
                if (bp != bq && n++ == 0) fx = x, fy = y, va = p, vb = q;
            }
        if (n)
            o << a.channelNames()[c] << ": " << n << " pixels differ (first (" << fx << "," << fy << ") " << va
              << " vs " << vb << "); ";
    }
    return o.str();
}

inline double Luminance(const Image &rgb, int x, int y) {
    return 0.2126 * rgb.at(x, y, 0) + 0.7152 * rgb.at(x, y, 1) + 0.0722 * rgb.at(x, y, 2);
}

// ---------------------------------------------------------------- statistics

// Regularised incomplete beta function I_x(a, b) (continued fraction, modified Lentz).
inline double IncompleteBeta(double a, double b, double x) {
    if (x <= 0) return 0;
    if (x >= 1) return 1;
    auto cf = [](double a, double b, double x) {
        const double tiny = 1e-300, eps = 1e-15;
        double c = 1, d = 1 - (a + b) * x / (a + 1);
        if (std::abs(d) < tiny) d = tiny;
        d = 1 / d;
        double h = d;
        for (int m = 1; m <= 1000; ++m) {
            for (int half = 0; half < 2; ++half) {
                double num = half == 0 ? m * (b - m) * x / ((a + 2 * m - 1) * (a + 2 * m))
                                       : -(a + m) * (a + b + m) * x / ((a + 2 * m) * (a + 2 * m + 1));
                d = 1 + num * d;
                if (std::abs(d) < tiny) d = tiny;
                c = 1 + num / c;
                if (std::abs(c) < tiny) c = tiny;
                d = 1 / d;
                h *= d * c;
                if (half == 1 && std::abs(d * c - 1) < eps) return h;
            }
        }
        return h;
    };
    double lbt = std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b) + a * std::log(x) + b * std::log1p(-x);
    if (x < (a + 1) / (a + b + 2)) return std::exp(lbt) * cf(a, b, x) / a;
    return 1 - std::exp(lbt) * cf(b, a, 1 - x) / b;
}

// P(|T| >= t) for Student's t with `dof` degrees of freedom (real dof > 0).
inline double StudentTwoSidedP(double t, double dof) {
    if (!std::isfinite(t)) return 0;
    return IncompleteBeta(dof / 2, 0.5, dof / (dof + t * t));
}

// The |t| whose two-sided tail probability is p (bisection).
inline double StudentCritical(double p, double dof) {
    double lo = 0, hi = 1e7;
    for (int i = 0; i < 200; ++i) {
        double mid = 0.5 * (lo + hi);
        (StudentTwoSidedP(mid, dof) > p ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
}

// Welch's two-sample t statistic of the means of a and b, with the
// Welch-Satterthwaite degrees of freedom.
struct Welch {
    double t = 0, dof = 1, diff = 0, se = 0;
    double meanA = 0, meanB = 0, seA = 0, seB = 0;  // per-sample means and their standard errors
    double p = 1;  // two-sided
};
inline Welch WelchTest(const std::vector<double> &a, const std::vector<double> &b) {
    auto moments = [](const std::vector<double> &v, double *mean, double *varOfMean) {
        double m = 0;
        for (double x : v) m += x;
        m /= v.size();
        double s2 = 0;
        for (double x : v) s2 += (x - m) * (x - m);
        s2 /= (v.size() - 1);
        *mean = m;
        *varOfMean = s2 / v.size();
    };
    double ma, va, mb, vb;
    moments(a, &ma, &va);
    moments(b, &mb, &vb);
    Welch w;
    w.diff = ma - mb;
    w.se = std::sqrt(va + vb);
    w.meanA = ma;
    w.meanB = mb;
    w.seA = std::sqrt(va);
    w.seB = std::sqrt(vb);
    if (!(va + vb > 0)) {  // both constant: identical means agree, different ones cannot
        w.t = w.diff == 0 ? 0 : INFINITY;
        w.p = w.diff == 0 ? 1 : 0;
        return w;
    }
    w.t = w.diff / w.se;
    w.dof = (va + vb) * (va + vb) / (va * va / (a.size() - 1) + vb * vb / (b.size() - 1));
    w.p = StudentTwoSidedP(w.t, w.dof);
    return w;
}

// Welch's t of mean(a) against the average of the means of several reference
// samples (a contrast): se^2 = var(mean a) + sum_r var(mean r) / R^2, degrees
// of freedom by Welch-Satterthwaite over every group's term. With one
// reference it is WelchTest.
inline Welch WelchContrast(const std::vector<double> &a, const std::vector<std::vector<double>> &refs) {
    if (refs.size() == 1) return WelchTest(a, refs[0]);
    auto moments = [](const std::vector<double> &v, double *mean, double *varOfMean) {
        double m = 0;
        for (double x : v) m += x;
        m /= v.size();
        double s2 = 0;
        for (double x : v) s2 += (x - m) * (x - m);
        *mean = m;
        *varOfMean = s2 / (v.size() - 1) / v.size();
    };
    Welch w;
    double va;
    moments(a, &w.meanA, &va);
    const double R = double(refs.size());
    double mb = 0, vb = 0, dofDen = va * va / (a.size() - 1);
    for (const auto &r : refs) {
        double m, v;
        moments(r, &m, &v);
        mb += m / R;
        vb += v / (R * R);
        dofDen += (v / (R * R)) * (v / (R * R)) / (r.size() - 1);
    }
    w.meanB = mb;
    w.seA = std::sqrt(va);
    w.seB = std::sqrt(vb);
    w.diff = w.meanA - mb;
    w.se = std::sqrt(va + vb);
    if (!(va + vb > 0)) {
        w.t = w.diff == 0 ? 0 : INFINITY;
        w.p = w.diff == 0 ? 1 : 0;
        return w;
    }
    w.t = w.diff / w.se;
    w.dof = (va + vb) * (va + vb) / dofDen;
    w.p = StudentTwoSidedP(w.t, w.dof);
    return w;
}

}  // namespace gradus::conformance
