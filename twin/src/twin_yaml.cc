#include "skerry/twin/twin_yaml.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <set>
#include <utility>
#include <vector>

#include "skerry/core/input_error.h"
#include "skerry/io/atomic_file.h"

namespace skerry {
namespace {

void Emit(YAML::Emitter* y, const char* key, const IdentifiedValue& v) {
  *y << YAML::Key << key << YAML::Value << YAML::Flow << YAML::BeginMap;
  *y << YAML::Key << "value" << YAML::Value << v.value;
  *y << YAML::Key << "sigma" << YAML::Value << v.sigma;
  *y << YAML::Key << "identified" << YAML::Value << v.identified;
  *y << YAML::EndMap;
}

void Emit(YAML::Emitter* y, const char* key, double v) {
  *y << YAML::Key << key << YAML::Value << v;
}

void EmitTiming(YAML::Emitter* y, const StreamTiming& t) {
  *y << YAML::Key << t.name << YAML::Value << YAML::BeginMap;
  *y << YAML::Key << "samples" << YAML::Value << t.samples;
  Emit(y, "duration_s", t.duration_s);
  Emit(y, "rate_hz", t.rate_hz);
  Emit(y, "period_jitter_s", t.period_jitter_s);
  *y << YAML::Key << "gaps" << YAML::Value << t.gaps;
  Emit(y, "longest_gap_s", t.longest_gap_s);
  Emit(y, "dropout_share", t.dropout_share);
  *y << YAML::Key << "gaps_over_2s" << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (const auto& [a, b] : t.gap_spans_s) {
    *y << YAML::Flow << YAML::BeginSeq << a << b << YAML::EndSeq;
  }
  *y << YAML::EndSeq << YAML::EndMap;
}

/// The model: section's keys, in the order written, each with the member it holds: one table
/// for the writer and the reader, so a key cannot be written and not read back. A key added
/// after twin.yaml files were written is optional when read (missing: the model's default, off),
/// so that those files still read.
struct ModelKey {
  const char* name;
  double* value;
  bool required = true;
};
using ModelSection = std::pair<const char*, std::vector<ModelKey>>;
std::vector<ModelSection> ModelKeys(sim::TwinModel* m) {
  return {{"imu",
           {{"gyro_noise_density_rad_s_sqrt_hz", &m->imu.gyro_noise_density_rad_s_sqrt_hz},
            {"accel_noise_density_m_s2_sqrt_hz", &m->imu.accel_noise_density_m_s2_sqrt_hz},
            {"gyro_bias_random_walk_rad_s2_sqrt_hz", &m->imu.gyro_bias_random_walk_rad_s2_sqrt_hz},
            {"accel_bias_random_walk_m_s3_sqrt_hz", &m->imu.accel_bias_random_walk_m_s3_sqrt_hz}}},
          {"gnss",
           {{"white_sigma_horizontal_m", &m->gnss.white_sigma_horizontal_m},
            {"white_sigma_vertical_m", &m->gnss.white_sigma_vertical_m},
            {"drift_sigma_horizontal_m", &m->gnss.drift_sigma_horizontal_m},
            {"drift_sigma_vertical_m", &m->gnss.drift_sigma_vertical_m},
            {"drift_tau_s", &m->gnss.drift_tau_s},
            {"gross_rate_per_hour", &m->gnss.gross_rate_per_hour},
            {"gross_mean_duration_s", &m->gnss.gross_mean_duration_s},
            {"gross_offset_horizontal_m", &m->gnss.gross_offset_horizontal_m},
            {"gross_offset_vertical_m", &m->gnss.gross_offset_vertical_m},
            {"latency_s", &m->gnss.latency_s},
            {"heading_sigma_deg", &m->gnss.heading_sigma_deg},
            {"solve_period_s", &m->gnss.solve_period_s, false},
            {"solve_phase_s", &m->gnss.solve_phase_s, false},
            {"solve_offset_sigma_m", &m->gnss.solve_offset_sigma_m, false},
            {"propagation_velocity_sigma_m_s", &m->gnss.propagation_velocity_sigma_m_s, false},
            {"propagation_velocity_tau_s", &m->gnss.propagation_velocity_tau_s, false}}}};
}

void EmitModel(YAML::Emitter* yp, const char* key, const sim::TwinModel& m) {
  YAML::Emitter& y = *yp;
  // Every digit: --model must give back the very twin this model made.
  y.SetDoublePrecision(17);
  y << YAML::Key << key << YAML::Value << YAML::BeginMap;
  sim::TwinModel copy = m;
  for (const auto& [section, members] : ModelKeys(&copy)) {
    y << YAML::Key << section << YAML::Value << YAML::BeginMap;
    for (const ModelKey& k : members) Emit(&y, k.name, *k.value);
    y << YAML::EndMap;
  }
  y << YAML::EndMap;
  y.SetDoublePrecision(6);
}

void EmitFidelity(YAML::Emitter* yp, const char* key, const TwinFidelity& f) {
  YAML::Emitter& y = *yp;
  y << YAML::Key << key << YAML::Value << YAML::BeginMap;
  y << YAML::Key << "twins" << YAML::Value << f.twins;
  y << YAML::Key << "twins_left_out" << YAML::Value << f.failed_twins;
  Emit(&y, "coverage", f.coverage);
  Emit(&y, "alpha", f.alpha);
  y << YAML::Key << "blocks" << YAML::Value << YAML::BeginMap;
  for (int b = 0; b < kNumFidelityBlocks; ++b) {
    const TwinFidelityBlock& x = f.blocks[b];
    y << YAML::Key << FidelityBlockName(static_cast<FidelityBlock>(b)) << YAML::Value << YAML::Flow
      << YAML::BeginMap;
    Emit(&y, "real_vs_twin_ahed", x.real_ahed);
    Emit(&y, "real_vs_twin_meandiff", x.real_meandiff);
    Emit(&y, "real_vs_twin_covdiff", x.real_covdiff);
    Emit(&y, "twin_vs_twin_ahed", x.twins_ahed);
    Emit(&y, "twin_vs_twin_sd", x.twins_sd);
    Emit(&y, "twin_vs_twin_max", x.twins_max);
    Emit(&y, "floor", x.floor);
    Emit(&y, "p_value", x.p_value);
    Emit(&y, "z", x.z);
    y << YAML::Key << "indistinguishable" << YAML::Value << x.indistinguishable;
    y << YAML::EndMap;
  }
  y << YAML::EndMap << YAML::EndMap;
}

void EmitStatistics(YAML::Emitter* yp,
                    const char* key,
                    const std::vector<StatisticComparison>& table) {
  YAML::Emitter& y = *yp;
  y << YAML::Key << key << YAML::Value << YAML::BeginSeq;
  for (const StatisticComparison& c : table) {
    y << YAML::Flow << YAML::BeginMap;
    y << YAML::Key << "statistic" << YAML::Value << c.name;
    Emit(&y, "real", c.real);
    Emit(&y, "twins_mean", c.twins_mean);
    Emit(&y, "twins_sd", c.twins_sd);
    Emit(&y, "twins_min", c.twins_min);
    Emit(&y, "twins_max", c.twins_max);
    Emit(&y, "p_value", c.p_value);
    y << YAML::Key << "indistinguishable" << YAML::Value << c.indistinguishable;
    y << YAML::EndMap;
  }
  y << YAML::EndSeq;
}

}  // namespace

void WriteTwinYaml(const std::string& path,
                   const Dataset& real,
                   const TwinIdentification& id,
                   const TwinProvenance& p,
                   const TwinFidelity* fidelity,
                   const TwinFidelity* before,
                   const TwinCalibration* calibration,
                   const sim::TwinModel* identified,
                   const GnssTrack* track,
                   const std::vector<StatisticComparison>* gnss_statistics,
                   const std::vector<StatisticComparison>* gnss_statistics_before) {
  YAML::Emitter y;
  y.SetDoublePrecision(6);
  y << YAML::Comment(
      "skerry twin: the sensor models of a recording, identified from it (docs/twin.md)");
  y << YAML::BeginMap;
  y << YAML::Key << "twin" << YAML::Value << YAML::BeginMap;
  y << YAML::Key << "recording" << YAML::Value << p.recording;
  y << YAML::Key << "config" << YAML::Value << p.config;
  y << YAML::Key << "truth" << YAML::Value
    << (track != nullptr ? "maximum-likelihood track through the fixes, as a cubic B-spline"
                         : "batch smoother trajectory through the recording, as a cubic B-spline");
  y << YAML::Key << "truth_keyframes" << YAML::Value << p.truth_keyframes;
  Emit(&y, "knot_s", p.knot_s);
  // Stamps of 1.7e9 s: six digits would say only the day.
  y.SetDoublePrecision(16);
  y << YAML::Key << "truth_span_s" << YAML::Value << YAML::Flow << YAML::BeginSeq << p.truth_start_s
    << p.truth_end_s << YAML::EndSeq;
  y.SetDoublePrecision(6);
  y << YAML::Key << "seed" << YAML::Value << p.seed;
  // The model: section is the calibrated one when a calibration ran from the identified model.
  y << YAML::Key << "model_source" << YAML::Value
    << (calibration == nullptr || p.model_source != "identified" ? p.model_source
        : calibration->validated                                 ? "calibrated from identified"
                                 : "identified (the calibration did not hold on held-out twins)");
  y << YAML::EndMap;

  if (id.imu_timing || id.gnss_timing) {
    y << YAML::Key << "timing" << YAML::Value << YAML::BeginMap;
    if (id.imu_timing) EmitTiming(&y, *id.imu_timing);
    if (id.gnss_timing) EmitTiming(&y, *id.gnss_timing);
    y << YAML::EndMap;
  }

  if (real.has_imu) {
    const ImuIdentification& imu = id.imu;
    y << YAML::Key << "imu" << YAML::Value << YAML::BeginMap;
    y << YAML::Key << "noise_source" << YAML::Value << imu.noise_source;
    if (imu.allan) {
      const ImuAllanReport& a = *imu.allan;
      y << YAML::Key << "rest" << YAML::Value << YAML::Flow << YAML::BeginMap;
      y << YAML::Key << "start_s" << YAML::Value
        << NsToSeconds(real.imu_samples[a.rest.begin].t_ns - real.imu_samples.front().t_ns);
      y << YAML::Key << "duration_s" << YAML::Value << a.rest.duration_s;
      y << YAML::EndMap;
    } else {
      y << YAML::Key << "rest" << YAML::Value << "none long enough for an Allan deviation";
    }
    Emit(&y, "gyro_noise_density_rad_s_sqrt_hz", imu.gyro_noise_density);
    Emit(&y, "accel_noise_density_m_s2_sqrt_hz", imu.accel_noise_density);
    Emit(&y, "gyro_bias_instability_rad_s", imu.gyro_bias_instability);
    Emit(&y, "accel_bias_instability_m_s2", imu.accel_bias_instability);
    Emit(&y, "gyro_bias_random_walk_rad_s2_sqrt_hz", imu.gyro_random_walk);
    Emit(&y, "accel_bias_random_walk_m_s3_sqrt_hz", imu.accel_random_walk);
    Emit(&y, "residual_gyro_noise_density_rad_s_sqrt_hz", imu.residual_gyro_density);
    Emit(&y, "residual_accel_noise_density_m_s2_sqrt_hz", imu.residual_accel_density);
    y << YAML::Key << "residual_samples" << YAML::Value << imu.residual_samples;
    const ImuNoise& n = real.imu.noise;
    y << YAML::Key << "dataset_yaml" << YAML::Value << YAML::BeginMap;
    Emit(&y, "gyro_noise_density_rad_s_sqrt_hz", n.gyro_noise_density_rad_s_sqrt_hz);
    Emit(&y, "accel_noise_density_m_s2_sqrt_hz", n.accel_noise_density_m_s2_sqrt_hz);
    Emit(&y, "gyro_bias_random_walk_rad_s2_sqrt_hz", n.gyro_bias_random_walk_rad_s2_sqrt_hz);
    Emit(&y, "accel_bias_random_walk_m_s3_sqrt_hz", n.accel_bias_random_walk_m_s3_sqrt_hz);
    y << YAML::EndMap << YAML::EndMap;
  }

  if (id.gnss) {
    const GnssErrorModelFit& g = *id.gnss;
    y << YAML::Key << "gnss" << YAML::Value << YAML::BeginMap;
    y << YAML::Key << "fixes" << YAML::Value << g.samples;
    y << YAML::Key << "outliers" << YAML::Value << g.outliers;
    Emit(&y, "period_s", g.period_s);
    Emit(&y, "latency_s", g.latency_s);
    Emit(&y, "white_sigma_horizontal_m", g.white_sigma_horizontal_m);
    Emit(&y, "white_sigma_vertical_m", g.white_sigma_vertical_m);
    Emit(&y, "drift_sigma_horizontal_m", g.drift_sigma_horizontal_m);
    Emit(&y, "drift_sigma_vertical_m", g.drift_sigma_vertical_m);
    Emit(&y, "drift_tau_s", g.drift_tau_s);
    if (!id.drift_detection.empty()) {
      // How much of a drift at each correlation time survives the batch, and the smallest drift
      // sigma the identification would have seen there (drift_detection.h).
      y << YAML::Key << "drift_detection" << YAML::Value << YAML::BeginSeq;
      for (const DriftDetection& d : id.drift_detection) {
        y << YAML::Flow << YAML::BeginMap;
        Emit(&y, "tau_s", d.tau_s);
        Emit(&y, "batch_gain_horizontal", d.batch_gain.horizontal);
        Emit(&y, "batch_gain_vertical", d.batch_gain.vertical);
        Emit(&y, "gain_limit_sigma_horizontal_m", d.gain_limit_sigma_horizontal_m);
        Emit(&y, "gain_limit_sigma_vertical_m", d.gain_limit_sigma_vertical_m);
        Emit(&y, "detectable_sigma_horizontal_m", d.detectable_sigma_horizontal_m);
        Emit(&y, "detectable_sigma_vertical_m", d.detectable_sigma_vertical_m);
        y << YAML::Key << "confirmed_horizontal" << YAML::Value << d.confirmed_horizontal;
        y << YAML::Key << "confirmed_vertical" << YAML::Value << d.confirmed_vertical;
        y << YAML::EndMap;
      }
      y << YAML::EndSeq;
    }
    Emit(&y, "residual_outlier_share", g.outlier_share);
    y << YAML::Key << "gross_errors" << YAML::Value << YAML::BeginMap;
    y << YAML::Key << "episodes" << YAML::Value << id.gross.episodes;
    y << YAML::Key << "fixes" << YAML::Value << id.gross.fixes;
    Emit(&y, "rate_per_hour", id.gross.rate_per_hour);
    Emit(&y, "mean_duration_s", id.gross.mean_duration_s);
    Emit(&y, "offset_horizontal_m", id.gross.offset_horizontal_m);
    Emit(&y, "offset_vertical_m", id.gross.offset_vertical_m);
    y << YAML::EndMap;
    if (id.heading.samples > 0) {
      y << YAML::Key << "heading_fixes" << YAML::Value << id.heading.samples;
      Emit(&y, "heading_sigma_deg", id.heading.sigma_deg);
    }
    if (id.solve_pattern) {
      // A receiver that solves once a period and propagates between (solve_pattern.h): the
      // best candidate's detection statistics, then the model's values when detected.
      const SolvePattern& sp = *id.solve_pattern;
      y << YAML::Key << "solve_pattern" << YAML::Value << YAML::BeginMap;
      y << YAML::Key << "detected" << YAML::Value << sp.detected;
      Emit(&y, "period_s", IdentifiedValue{sp.period_s, 0.0, sp.detected});
      Emit(&y, "phase_s", IdentifiedValue{sp.phase_s, 0.0, sp.detected});
      Emit(&y, "jump_ratio", sp.jump_ratio);
      Emit(&y, "jump_z", sp.jump_z);
      Emit(&y, "period_correlation", sp.period_correlation);
      Emit(&y, "half_period_correlation", sp.half_period_correlation);
      y << YAML::Key << "periods" << YAML::Value << sp.periods;
      Emit(&y, "white_sigma_horizontal_m", sp.white_sigma_horizontal_m);
      Emit(&y, "offset_sigma_m", sp.offset_sigma_m);
      Emit(&y, "propagation_velocity_sigma_m_s", sp.propagation_velocity_sigma_m_s);
      Emit(&y, "propagation_velocity_tau_s", sp.propagation_velocity_tau_s);
      y << YAML::EndMap;
    }
    y << YAML::EndMap;
  }

  EmitModel(&y, "model", id.model);
  if (calibration != nullptr && identified != nullptr) {
    EmitModel(&y, "identified_model", *identified);
    y << YAML::Key << "calibration" << YAML::Value << YAML::BeginMap;
    Emit(&y, "objective_before", calibration->objective_before);
    Emit(&y, "objective_after", calibration->objective_after);
    y << YAML::Key << "evaluations" << YAML::Value << calibration->evaluations;
    if (calibration->validation_twins > 0) {
      y << YAML::Key << "held_out" << YAML::Value << YAML::Flow << YAML::BeginMap;
      y << YAML::Key << "twins" << YAML::Value << calibration->validation_twins;
      Emit(&y, "objective_identified", calibration->validation_before);
      Emit(&y, "objective_calibrated", calibration->validation_after);
      y << YAML::Key << "calibrated_kept" << YAML::Value << calibration->validated;
      y << YAML::EndMap;
    }
    y << YAML::Key << "kept" << YAML::Value << YAML::BeginSeq;
    for (const TwinCalibrationStep& st : calibration->steps) {
      if (!st.kept) continue;
      y << YAML::Flow << YAML::BeginMap;
      y << YAML::Key << "parameter" << YAML::Value << st.parameter;
      Emit(&y, "value", st.value);
      Emit(&y, "objective", st.objective);
      y << YAML::EndMap;
    }
    y << YAML::EndSeq << YAML::EndMap;
  }
  if (track != nullptr) {
    y << YAML::Key << "track" << YAML::Value << YAML::BeginMap;
    y << YAML::Key << "truth" << YAML::Value
      << "maximum-likelihood nearly-constant-velocity track through the fixes (RTS smoother)";
    Emit(&y, "white_sigma_horizontal_m", track->white_sigma_horizontal_m);
    Emit(&y, "white_sigma_vertical_m", track->white_sigma_vertical_m);
    Emit(&y, "accel_psd_horizontal_m2_s3", track->accel_psd_horizontal);
    Emit(&y, "accel_psd_vertical_m2_s3", track->accel_psd_vertical);
    y << YAML::EndMap;
  }
  if (gnss_statistics != nullptr) EmitStatistics(&y, "gnss_statistics", *gnss_statistics);
  if (gnss_statistics_before != nullptr) {
    EmitStatistics(&y, "gnss_statistics_identified_model", *gnss_statistics_before);
  }
  if (fidelity != nullptr) EmitFidelity(&y, "fidelity", *fidelity);
  if (before != nullptr) EmitFidelity(&y, "fidelity_identified_model", *before);
  y << YAML::EndMap;
  WriteFileAtomically(path, std::string(y.c_str()) + "\n");
}

YAML::Node LoadTwinYamlDocument(const std::string& path) {
  try {
    return YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw InputError(path, 0, "", "cannot open the file");
  } catch (const YAML::Exception& e) {
    throw InputError(path, e.mark.line + 1, "", e.msg);
  }
}

sim::TwinModel ReadTwinModel(const std::string& path) {
  const YAML::Node root = LoadTwinYamlDocument(path);
  // A document that is not a map (a scalar, a sequence): yaml-cpp throws on operator[].
  if (!root.IsMap()) throw InputError(path, 1, "(document)", "not a map with a model: section");
  const YAML::Node model = root["model"];
  if (!model || !model.IsMap()) throw InputError(path, 0, "model", "missing (a map)");
  sim::TwinModel m;
  for (const auto& [section, members] : ModelKeys(&m)) {
    const YAML::Node s = model[section];
    const std::string where = std::string("model.") + section;
    if (!s || !s.IsMap()) throw InputError(path, model.Mark().line + 1, where, "missing (a map)");
    std::set<std::string> known;
    for (const auto& [key, target, required] : members) {
      known.insert(key);
      const YAML::Node v = s[key];
      if (!v && !required) continue;
      if (!v) throw InputError(path, s.Mark().line + 1, where + "." + key, "missing");
      double x = 0.0;
      try {
        x = v.as<double>();
      } catch (const YAML::Exception&) {
        throw InputError(path, v.Mark().line + 1, where + "." + key, "not a number");
      }
      if (!std::isfinite(x) || x < 0.0) {
        throw InputError(path, v.Mark().line + 1, where + "." + key, "must be finite and >= 0");
      }
      *target = x;
    }
    for (const auto& kv : s) {
      if (!kv.first.IsScalar()) {
        throw InputError(path, kv.first.Mark().line + 1, where, "a key must be a plain name");
      }
      const std::string k = kv.first.Scalar();
      if (known.count(k) == 0) {
        throw InputError(path, kv.first.Mark().line + 1, where + "." + k, "unknown key");
      }
    }
  }
  if (!(m.gnss.drift_tau_s > 0.0)) {
    throw InputError(path, 0, "model.gnss.drift_tau_s", "must be > 0");
  }
  if (!(m.gnss.propagation_velocity_tau_s > 0.0)) {
    const YAML::Node gnss = model["gnss"];
    const YAML::Node v = gnss["propagation_velocity_tau_s"];
    throw InputError(path, v ? v.Mark().line + 1 : gnss.Mark().line + 1,
                     "model.gnss.propagation_velocity_tau_s", "must be > 0");
  }
  return m;
}

}  // namespace skerry
