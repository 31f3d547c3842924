function bailey_parity_driver(bailey_dir, sim_dir, filter, nparticles, seed, out_csv, weights, predict_mode)
% Runs Tim Bailey's MATLAB FastSLAM 1.0 or 2.0 on the noisy controls and observations of a
% `grove fastslam simulate` directory instead of the noise his simulator loop draws itself.
% The loop is his fastslam1_sim.m / fastslam2_sim.m with the simulator's parts replaced by the
% CSV rows; every filter step is a call of his own functions, with his configfile.m's settings.
%
%   octave-cli --no-gui -q --eval "addpath('bench/studies'); bailey_parity_driver( ...
%       BAILEY_FASTSLAM_DIR, SIM_DIR, 'fastslam2', 100, 1, 'OUT.csv', 'log' [, 'percall'])"
%
% weights 'linear' runs his weight code as it is (sample_proposal.m, compute_weight.m): products
% of densities, which underflow to 0 in every particle when a loop closes with a few metres of
% drift, and his resampling then divides 0 by 0. 'log' keeps each particle's weight as a
% logarithm with his formulas (his gauss_evaluate's log form) and hands resample_particles.m
% exp(log w - max log w); the proposal, the draw and everything else are his.
%
% Writes OUT.csv (t,x,y,heading: the weighted-mean pose at the start, after every control step
% and after every scan, as grove's trajectory.csv) and OUT.csv.params (his settings as used).

% His `&` in if and while conditions is MATLAB's short-circuit form: correct, and warned about
% by Octave at every call.
warning('off', 'Octave:possible-matlab-short-circuit-operator');
addpath(bailey_dir);
addpath(fullfile(bailey_dir, filter));
configfile;  % his settings: V, WHEELBASE, DT_CONTROLS, Q, R, NEFFECTIVE, SWITCH_*
NPARTICLES = nparticles;
NEFFECTIVE = 0.75 * NPARTICLES;  % his configfile's rule, at this particle count
fs1 = strcmp(filter, 'fastslam1');
if fs1
  % His configfile leaves this 0 (his FastSLAM 2.0 setting); his fastslam1_sim.m warns that
  % FastSLAM 1.0 needs it for any particle diversity.
  SWITCH_PREDICT_NOISE = 1;
end
Qe = Q; Re = R;
if SWITCH_INFLATE_NOISE == 1, Qe = 2 * Q; Re = 2 * R; end
rand('state', seed);
randn('state', seed);

controls = dlmread(fullfile(sim_dir, 'controls.csv'), ',', 1, 0);
obs = dlmread(fullfile(sim_dir, 'observations.csv'), ',', 1, 0);
nlm = size(dlmread(fullfile(sim_dir, 'landmarks_truth.csv'), ',', 1, 0), 1);

particles = struct('w', {}, 'xv', {}, 'Pv', {}, 'xf', {}, 'Pf', {}, 'da', {});
for i = 1:NPARTICLES
  particles(i).w = 1 / NPARTICLES;
  particles(i).xv = [0; 0; 0];
  particles(i).Pv = zeros(3);
  particles(i).xf = [];
  particles(i).Pf = [];
  particles(i).da = [];
end
da_table = zeros(1, nlm);
log_weights = strcmp(weights, 'log');
lw = zeros(1, NPARTICLES);
% 'vectorised' moves all particles at once with his predict.m's equations (predict_all below):
% his per-particle calls cost about 85 % of a run under Octave.
vectorised = nargin < 8 || strcmp(predict_mode, 'vectorised');
xv = zeros(3, NPARTICLES);
Pv = zeros(3, 3, NPARTICLES);

K = size(controls, 1);
M = size(obs, 1);
out = zeros(K + sum(diff([-1; obs(:, 1)]) > 0) + 1, 4);
nout = 1;
out(1, :) = [controls(1, 1), mean_pose(particles, lw, log_weights)'];
ptr = 1;
for k = 1:(K - 1)
  Vn = controls(k, 2); Gn = controls(k, 3);
  t_next = controls(k + 1, 1);
  dt = t_next - controls(k, 1);
  if vectorised
    [xv, Pv] = predict_all(xv, Pv, Vn, Gn, Qe, WHEELBASE, dt, SWITCH_PREDICT_NOISE, fs1);
  else
    for i = 1:NPARTICLES
      particles(i) = predict(particles(i), Vn, Gn, Qe, WHEELBASE, dt, SWITCH_PREDICT_NOISE);
    end
  end
  nout = nout + 1;
  if vectorised
    out(nout, :) = [t_next, mean_xv(xv, lw, log_weights, particles)'];
  else
    out(nout, :) = [t_next, mean_pose(particles, lw, log_weights)'];
  end

  last = ptr - 1;
  while last < M && abs(obs(last + 1, 1) - t_next) < 1e-9
    last = last + 1;
  end
  if last < ptr, continue, end
  z = obs(ptr:last, 2:3)';
  ftag_visible = obs(ptr:last, 4)' + 1;
  ptr = last + 1;

  if vectorised
    for i = 1:NPARTICLES
      particles(i).xv = xv(:, i);
      particles(i).Pv = Pv(:, :, i);
    end
  end
  Nf = size(particles(1).xf, 2);
  [zf, idf, zn, da_table] = data_associate_known(z, ftag_visible, da_table, Nf);
  if fs1
    for i = 1:NPARTICLES
      if ~isempty(zf)
        if log_weights
          lw(i) = lw(i) + log_likelihood(particles(i), zf, idf, R);
        else
          particles(i).w = particles(i).w * compute_weight(particles(i), zf, idf, R);
        end
        particles(i) = feature_update(particles(i), zf, idf, R);
      end
      if ~isempty(zn)
        particles(i) = add_feature(particles(i), zn, R);
      end
    end
    [particles, lw] = resample(particles, lw, log_weights, NEFFECTIVE, SWITCH_RESAMPLE);
  else
    if ~isempty(zf)
      for i = 1:NPARTICLES
        if log_weights
          [particles(i), dlw] = sample_proposal_log(particles(i), zf, idf, Re);
          lw(i) = lw(i) + dlw;
        else
          particles(i) = sample_proposal(particles(i), zf, idf, Re);
        end
        particles(i) = feature_update(particles(i), zf, idf, Re);
      end
      [particles, lw] = resample(particles, lw, log_weights, NEFFECTIVE, SWITCH_RESAMPLE);
    end
    if ~isempty(zn)
      for i = 1:NPARTICLES
        if isempty(zf)
          particles(i).xv = multivariate_gauss(particles(i).xv, particles(i).Pv, 1);
          particles(i).Pv = zeros(3);
        end
        particles(i) = add_feature(particles(i), zn, Re);
      end
    end
  end
  if vectorised
    xv = [particles.xv];
    Pv = reshape([particles.Pv], 3, 3, NPARTICLES);
  end
  nout = nout + 1;
  out(nout, :) = [t_next, mean_pose(particles, lw, log_weights)'];
end
if ptr <= M
  error('observation at t = %g matches no control time', obs(ptr, 1));
end

f = fopen(out_csv, 'w');
fprintf(f, 't,x,y,heading\n');
fprintf(f, '%.17g,%.17g,%.17g,%.17g\n', out(1:nout, :)');
fclose(f);
f = fopen([out_csv '.params'], 'w');
fprintf(f, 'wheelbase_m=%.17g\nsigma_speed_mps=%.17g\nsigma_steer_rad=%.17g\n', ...
        WHEELBASE, sqrt(Q(1, 1)), sqrt(Q(2, 2)));
fprintf(f, 'sigma_range_m=%.17g\nsigma_bearing_rad=%.17g\n', sqrt(R(1, 1)), sqrt(R(2, 2)));
fprintf(f, 'dt_controls_s=%.17g\ndt_observe_s=%.17g\nmax_range_m=%.17g\n', ...
        DT_CONTROLS, DT_OBSERVE, MAX_RANGE);
fprintf(f, 'neffective_fraction=%.17g\ninflate_noise=%d\npredict_noise=%d\n', ...
        NEFFECTIVE / NPARTICLES, SWITCH_INFLATE_NOISE, SWITCH_PREDICT_NOISE);
fprintf(f, 'heading_known=%d\nresample=%d\nweights=%s\n', SWITCH_HEADING_KNOWN, ...
        SWITCH_RESAMPLE, weights);
fclose(f);
end

function m = mean_pose(particles, lw, log_weights)
m = mean_xv([particles.xv], lw, log_weights, particles);
end

function m = mean_xv(xv, lw, log_weights, particles)
if log_weights
  w = exp(lw - max(lw));
else
  w = [particles.w];
end
w = w / sum(w);
m = [xv(1:2, :) * w'; atan2(sin(xv(3, :)) * w', cos(xv(3, :)) * w')];
end

function [particles, lw] = resample(particles, lw, log_weights, neffective, doresample)
% His resample_particles.m; under log weights it gets the weights scaled by exp(-max log w).
if log_weights
  for i = 1:numel(particles), particles(i).w = exp(lw(i) - max(lw)); end
end
particles = resample_particles(particles, neffective, doresample);
if log_weights, lw = log([particles.w]); end
end

function l = log_likelihood(particle, z, idf, R)
% His fastslam1/compute_weight.m as a logarithm.
[zp, Hv, Hf, Sf] = compute_jacobians(particle, idf, R);
v = z - zp;
v(2, :) = pi_to_pi(v(2, :));
l = 0;
for i = 1:size(z, 2)
  S = Sf(:, :, i);
  l = l - log(2 * pi * sqrt(det(S))) - 0.5 * v(:, i)' * (S \ v(:, i));
end
end

function [particle, dlw] = sample_proposal_log(particle, z, idf, R)
% His fastslam2/sample_proposal.m line by line, its weight like * prior / prop as a logarithm.
xv = particle.xv;
Pv = particle.Pv;
xv0 = xv;
Pv0 = Pv;
for i = 1:length(idf)
  [zpi, Hvi, Hfi, Sf] = compute_jacobians(particle, idf(i), R);
  Sfi = inv(Sf);
  vi = z(:, i) - zpi;
  vi(2) = pi_to_pi(vi(2));
  Pv = inv(Hvi' * Sfi * Hvi + inv(Pv));
  xv = xv + Pv * Hvi' * Sfi * vi;
  particle.xv = xv;
  particle.Pv = Pv;
end
xvs = multivariate_gauss(xv, Pv, 1);
particle.xv = xvs;
particle.Pv = zeros(3);
like = 0;
for i = 1:length(idf)
  [zp, Hv, Hf, Sf] = compute_jacobians(particle, idf(i), R);
  v = z(:, i) - zp;
  v(2) = pi_to_pi(v(2));
  like = like + gauss_evaluate(v, Sf, 1);
end
prior = gauss_evaluate(delta_xv(xv0, xvs), Pv0, 1);
prop = gauss_evaluate(delta_xv(xv, xvs), Pv, 1);
dlw = like + prior - prop;
end

function dx = delta_xv(xv1, xv2)
dx = xv1 - xv2;
dx(3, :) = pi_to_pi(dx(3, :));
end

function [xv, Pv] = predict_all(xv, Pv, V, G, Q, WB, dt, addrandom, fs1)
% His fastslam1/predict.m (fs1) or fastslam2/predict.m on every column of xv at once: the same
% arithmetic; the control draws of FastSLAM 1.0 are his multivariate_gauss's, one column a
% particle, in his order.
n = size(xv, 2);
V = V * ones(1, n);
G = G * ones(1, n);
if ~fs1
  c = cos(G + xv(3, :)); s = sin(G + xv(3, :));
  a = -V .* dt .* s; b = V .* dt .* c;
  M = Pv;
  M(1, :, :) = Pv(1, :, :) + reshape(a, 1, 1, n) .* Pv(3, :, :);
  M(2, :, :) = Pv(2, :, :) + reshape(b, 1, 1, n) .* Pv(3, :, :);
  P = M;
  P(:, 1, :) = M(:, 1, :) + reshape(a, 1, 1, n) .* M(:, 3, :);
  P(:, 2, :) = M(:, 2, :) + reshape(b, 1, 1, n) .* M(:, 3, :);
  u = zeros(3, 2, n);
  u(:, 1, :) = reshape([dt * c; dt * s; dt * sin(G) / WB], 3, 1, n);
  u(:, 2, :) = reshape([-V .* dt .* s; V .* dt .* c; V .* dt .* cos(G) / WB], 3, 1, n);
  for k = 1:2
    for l = 1:2
      P = P + Q(k, l) * u(:, k, :) .* reshape(u(:, l, :), 1, 3, n);
    end
  end
  Pv = P;
end
if addrandom == 1
  VG = chol(Q)' * randn(2, n) + [V(1); G(1)] * ones(1, n);
  V = VG(1, :); G = VG(2, :);
end
xv = [xv(1, :) + V .* dt .* cos(G + xv(3, :));
      xv(2, :) + V .* dt .* sin(G + xv(3, :));
      pi_to_pi(xv(3, :) + V .* dt .* sin(G) / WB)];
end
