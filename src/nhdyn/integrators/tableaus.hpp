// The Butcher tableaus of nhdyn's explicit Runge-Kutta methods, as constexpr data: the classic
// RK4, Dormand-Prince 5(4) as in Hairer's DOPRI5 and Dormand-Prince 8(5,3) as in Hairer's DOP853
// (Hairer, Norsett, Wanner, "Solving Ordinary Differential Equations I", II.4-II.6 and II.10), with
// the constants of their step-size control, error estimates and continuous extensions. The one
// stepper of integrators/ (integrate(), ode.hpp) runs them; they are public so that a program can
// use the same coefficients (bench/check/sled_by_hand.hpp integrates the sled by hand with them).
#pragma once

#include <array>

namespace nhdyn {
namespace rk {

// A tableau is a struct of constexpr data: stages, order, fsal (the last stage is f at the new
// state, so it is the next step's first stage), c (nodes), a (stage weights, strictly lower
// triangular), b (weights of the solution). Adaptive tableaus add e = b - b_hat (weights of the
// error estimate) and the order of the embedded solution.

struct ClassicRk4 {
  static constexpr int stages = 4;
  static constexpr int order = 4;
  static constexpr bool fsal = false;
  static constexpr std::array<double, stages> c{{0.0, 0.5, 0.5, 1.0}};
  static constexpr std::array<std::array<double, stages>, stages> a{{
      {{0.0, 0.0, 0.0, 0.0}},
      {{0.5, 0.0, 0.0, 0.0}},
      {{0.0, 0.5, 0.0, 0.0}},
      {{0.0, 0.0, 1.0, 0.0}},
  }};
  static constexpr std::array<double, stages> b{{1.0 / 6.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 6.0}};
};

// Dormand & Prince (1980), coefficients as in Hairer's DOPRI5.
struct DormandPrince54 {
  static constexpr int stages = 7;
  static constexpr int order = 5;
  static constexpr int embedded_order = 4;
  static constexpr bool fsal = true;
  // Hairer's DOPRI5 step-size control: PI control with beta = 0.04, the new step within
  // [h / 5, 10 h], safety factor 0.9; the error estimate is O(h^5).
  static constexpr double beta = 0.04;
  static constexpr double exponent = 1.0 / 5.0 - 0.75 * beta;
  static constexpr double fac_min = 0.2;
  static constexpr double fac_max = 10.0;
  static constexpr double safety = 0.9;
  // Where the stability region meets the negative real axis, for the stiffness test (DOPRI5's 3.25).
  static constexpr double stability_bound = 3.25;
  static constexpr std::array<double, stages> c{{0.0, 0.2, 0.3, 0.8, 8.0 / 9.0, 1.0, 1.0}};
  static constexpr std::array<std::array<double, stages>, stages> a{{
      {{0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0}},
      {{0.2, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0}},
      {{3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0, 0.0}},
      {{44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0, 0.0}},
      {{19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0, 0.0, 0.0, 0.0}},
      {{9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0, 0.0,
        0.0}},
      {{35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0, 0.0}},
  }};
  static constexpr std::array<double, stages> b{
      {35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0, 0.0}};
  static constexpr std::array<double, stages> e{{71.0 / 57600.0, 0.0, -71.0 / 16695.0,
                                                71.0 / 1920.0, -17253.0 / 339200.0, 22.0 / 525.0,
                                                -1.0 / 40.0}};
  // Continuous extension of order 4 (Hairer's CONTD5): a cubic Hermite interpolant through
  // (y0, f0) and (y1, f1) plus theta^2 (1 - theta)^2 times h sum d_i k_i.
  static constexpr std::array<double, stages> d{
      {-12715105075.0 / 11282082432.0, 0.0, 87487479700.0 / 32700410799.0,
       -10690763975.0 / 1880347072.0, 701980252875.0 / 199316789632.0,
       -1453857185.0 / 822651844.0, 69997945.0 / 29380423.0}};
};

// Dormand & Prince's 8(5,3) pair (Prince & Dormand 1981), coefficients as in Hairer's DOP853
// (Hairer-Norsett-Wanner I, II.10): 12 stages of the 8th-order solution plus the FSAL stage
// f(t + h, y1), which the error estimate does not use and so is evaluated only for accepted steps.
// The error is estimated by a 5th-order and a 3rd-order embedded solution together (see
// dop853_error in explicit_rk.cpp). The continuous extension of order 7 needs 3 more stages, which
// cost 3 rhs evaluations in the steps that hold an output time and none in the others.
struct DormandPrince853 {
  static constexpr int stages = 13;
  static constexpr int order = 8;
  static constexpr int embedded_order = 5;
  static constexpr bool fsal = true;
  static constexpr int extra_stages = 3;
  static constexpr int all_stages = stages + extra_stages;
  // Hairer's DOP853 step-size control: no PI term (beta = 0), the new step within [0.333 h, 6 h],
  // safety factor 0.9; the combined error estimate is O(h^8).
  static constexpr double beta = 0.0;
  static constexpr double exponent = 1.0 / 8.0 - 0.2 * beta;
  static constexpr double fac_min = 0.333;
  static constexpr double fac_max = 6.0;
  static constexpr double safety = 0.9;
  static constexpr double stability_bound = 6.1;  // DOP853's, for the stiffness test
  static constexpr std::array<double, stages> c{
      {0.0, 0.526001519587677318785587544488e-01, 0.789002279381515978178381316732e-01,
       0.118350341907227396726757197510, 0.281649658092772603273242802490,
       0.333333333333333333333333333333, 0.25, 0.307692307692307692307692307692,
       0.651282051282051282051282051282, 0.6, 0.857142857142857142857142857142, 1.0, 1.0}};
  static constexpr std::array<std::array<double, stages>, stages> a{{
      {{0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0}},
      {{5.26001519587677318785587544488e-2, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
        0.0}},
      {{1.97250569845378994544595329183e-2, 5.91751709536136983633785987549e-2, 0.0, 0.0, 0.0, 0.0,
        0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0}},
      {{2.95875854768068491816892993775e-2, 0.0, 8.87627564304205475450678981324e-2, 0.0, 0.0, 0.0,
        0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0}},
      {{2.41365134159266685502369798665e-1, 0.0, -8.84549479328286085344864962717e-1,
        9.24834003261792003115737966543e-1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0}},
      {{3.7037037037037037037037037037e-2, 0.0, 0.0, 1.70828608729473871279604482173e-1,
        1.25467687566822425016691814123e-1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0}},
      {{3.7109375e-2, 0.0, 0.0, 1.70252211019544039314978060272e-1,
        6.02165389804559606850219397283e-2, -1.7578125e-2, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0}},
      {{3.70920001185047927108779319836e-2, 0.0, 0.0, 1.70383925712239993810214054705e-1,
        1.07262030446373284651809199168e-1, -1.53194377486244017527936158236e-2,
        8.27378916381402288758473766002e-3, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0}},
      {{6.24110958716075717114429577812e-1, 0.0, 0.0, -3.36089262944694129406857109825,
        -8.68219346841726006818189891453e-1, 2.75920996994467083049415600797e1,
        2.01540675504778934086186788979e1, -4.34898841810699588477366255144e1, 0.0, 0.0, 0.0, 0.0,
        0.0}},
      {{4.77662536438264365890433908527e-1, 0.0, 0.0, -2.48811461997166764192642586468,
        -5.90290826836842996371446475743e-1, 2.12300514481811942347288949897e1,
        1.52792336328824235832596922938e1, -3.32882109689848629194453265587e1,
        -2.03312017085086261358222928593e-2, 0.0, 0.0, 0.0, 0.0}},
      {{-9.3714243008598732571704021658e-1, 0.0, 0.0, 5.18637242884406370830023853209,
        1.09143734899672957818500254654, -8.14978701074692612513997267357,
        -1.85200656599969598641566180701e1, 2.27394870993505042818970056734e1,
        2.49360555267965238987089396762, -3.0467644718982195003823669022, 0.0, 0.0, 0.0}},
      {{2.27331014751653820792359768449, 0.0, 0.0, -1.05344954667372501984066689879e1,
        -2.00087205822486249909675718444, -1.79589318631187989172765950534e1,
        2.79488845294199600508499808837e1, -2.85899827713502369474065508674,
        -8.87285693353062954433549289258, 1.23605671757943030647266201528e1,
        6.43392746015763530355970484046e-1, 0.0, 0.0}},
      {{5.42937341165687622380535766363e-2, 0.0, 0.0, 0.0, 0.0, 4.45031289275240888144113950566,
        1.89151789931450038304281599044, -5.8012039600105847814672114227,
        3.1116436695781989440891606237e-1, -1.52160949662516078556178806805e-1,
        2.01365400804030348374776537501e-1, 4.47106157277725905176885569043e-2, 0.0}},
  }};
  static constexpr std::array<std::array<double, all_stages>, extra_stages> a_extra{{
      {{5.61675022830479523392909219681e-2, 0.0, 0.0, 0.0, 0.0, 0.0,
        2.53500210216624811088794765333e-1, -2.46239037470802489917441475441e-1,
        -1.24191423263816360469010140626e-1, 1.5329179827876569731206322685e-1,
        8.20105229563468988491666602057e-3, 7.56789766054569976138603589584e-3, -8.298e-3, 0.0, 0.0,
        0.0}},
      {{3.18346481635021405060768473261e-2, 0.0, 0.0, 0.0, 0.0, 2.83009096723667755288322961402e-2,
        5.35419883074385676223797384372e-2, -5.49237485713909884646569340306e-2, 0.0, 0.0,
        -1.08347328697249322858509316994e-4, 3.82571090835658412954920192323e-4,
        -3.40465008687404560802977114492e-4, 1.41312443674632500278074618366e-1, 0.0, 0.0}},
      {{-4.28896301583791923408573538692e-1, 0.0, 0.0, 0.0, 0.0, -4.69762141536116384314449447206,
        7.68342119606259904184240953878, 4.06898981839711007970213554331,
        3.56727187455281109270669543021e-1, 0.0, 0.0, 0.0, -1.39902416515901462129418009734e-3,
        2.9475147891527723389556272149, -9.15095847217987001081870187138, 0.0}},
  }};
  static constexpr std::array<double, stages> b = a[stages - 1];
  // Weights of the 5th-order error estimate: b - b_hat5.
  static constexpr std::array<double, stages> e5{
      {0.1312004499419488073250102996e-1, 0.0, 0.0, 0.0, 0.0, -0.1225156446376204440720569753e1,
       -0.4957589496572501915214079952, 0.1664377182454986536961530415e1,
       -0.3503288487499736816886487290, 0.3341791187130174790297318841,
       0.8192320648511571246570742613e-1, -0.2235530786388629525884427845e-1, 0.0}};
  // Weights of the 3rd-order embedded solution; its error estimate is b - bhh.
  static constexpr std::array<double, stages> bhh{
      {0.244094488188976377952755905512, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
       0.733846688281611857341361741547, 0.0, 0.0, 0.220588235294117647058823529412e-1, 0.0}};
  static constexpr std::array<double, extra_stages> c_extra{
      {0.1, 0.2, 0.777777777777777777777777777778}};
  // The 4 highest coefficients of the interpolating polynomial in units of h k_j (Hairer's
  // CONTD8); the 3 lowest come from y, y1, f(t, y) and f(t + h, y1).
  static constexpr std::array<std::array<double, all_stages>, 4> d{{
      {{-0.84289382761090128651353491142e1, 0.0, 0.0, 0.0, 0.0, 0.56671495351937776962531783590,
        -0.30689499459498916912797304727e1, 0.23846676565120698287728149680e1,
        0.21170345824450282767155149946e1, -0.87139158377797299206789907490,
        0.22404374302607882758541771650e1, 0.63157877876946881815570249290,
        -0.88990336451333310820698117400e-1, 0.18148505520854727256656404962e2,
        -0.91946323924783554000451984436e1, -0.44360363875948939664310572000e1}},
      {{0.10427508642579134603413151009e2, 0.0, 0.0, 0.0, 0.0, 0.24228349177525818288430175319e3,
        0.16520045171727028198505394887e3, -0.37454675472269020279518312152e3,
        -0.22113666853125306036270938578e2, 0.77334326684722638389603898808e1,
        -0.30674084731089398182061213626e2, -0.93321305264302278729567221706e1,
        0.15697238121770843886131091075e2, -0.31139403219565177677282850411e2,
        -0.93529243588444783865713862664e1, 0.35816841486394083752465898540e2}},
      {{0.19985053242002433820987653617e2, 0.0, 0.0, 0.0, 0.0, -0.38703730874935176555105901742e3,
        -0.18917813819516756882830838328e3, 0.52780815920542364900561016686e3,
        -0.11573902539959630126141871134e2, 0.68812326946963000169666922661e1,
        -0.10006050966910838403183860980e1, 0.77771377980534432092869265740,
        -0.27782057523535084065932004339e1, -0.60196695231264120758267380846e2,
        0.84320405506677161018159903784e2, 0.11992291136182789328035130030e2}},
      {{-0.25693933462703749003312586129e2, 0.0, 0.0, 0.0, 0.0, -0.15418974869023643374053993627e3,
        -0.23152937917604549567536039109e3, 0.35763911791061412378285349910e3,
        0.93405324183624310003907691704e2, -0.37458323136451633156875139351e2,
        0.10409964950896230045147246184e3, 0.29840293426660503123344363579e2,
        -0.43533456590011143754432175058e2, 0.96324553959188282948394950600e2,
        -0.39177261675615439165231486172e2, -0.14972683625798562581422125276e3}},
  }};
};

}  // namespace rk

}  // namespace nhdyn
