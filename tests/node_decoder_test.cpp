// The fixed-point node decoder against the double reference decoder: every
// node of several models, each field within its quantization step, and the
// Q14 frame decode against the reference frame for every angle code — and
// the renderer's Euler-form frames, in camera space, against the same.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/node_decoder.h"
#include "raster/node_setup.h"
#include "test_util.h"
#include "tools/encoder/quantize.h"

namespace stipple {
namespace {

struct Case {
  const char* name;
  PointCloud cloud;
  EncodeOptions options;
};

std::vector<Case> cases() {
  std::vector<Case> out;
  out.push_back({"sphere, normals", test::sphere_cloud(3000), {}});
  PointCloud colored = test::sphere_cloud(2000);
  for (const Vec3& p : colored.positions) colored.colors.push_back(((p + Vec3::Ones()) / 2).cwiseProduct(Vec3(1, 0.6, 0.3)));
  out.push_back({"sphere, colour", colored, {}});
  EncodeOptions no_normals;
  no_normals.normals = false;
  out.push_back({"sphere, no normals", test::sphere_cloud(1500), no_normals});
  PointCloud far = test::sphere_cloud(2000, 3.0);
  for (Vec3& p : far.positions) p += Vec3(1e6, -2e5, 4e4);  // float32 box far from the origin
  out.push_back({"far from origin", far, {}});
  PointCloud flat;
  for (int i = 0; i < 40; ++i)
    for (int j = 0; j < 40; ++j) {
      flat.positions.push_back(Vec3(i * 0.01, j * 0.02, 0.0));  // zero extent along z
      flat.normals.push_back(Vec3::UnitZ());
    }
  out.push_back({"flat", flat, {}});
  PointCloud bunny;
  std::string error;
  EXPECT_TRUE(read_point_cloud(test::source_path("data/bunny.ply"), bunny, error)) << error;
  out.push_back({"bunny", bunny, {}});
  return out;
}

TEST(NodeDecoder, EveryNodeMatchesTheReferenceDecoder) {
  for (const Case& c : cases()) {
    SCOPED_TRACE(c.name);
    const std::vector<uint8_t> spg = test::encode(c.cloud, c.options);
    const DecodedModel ref = test::decode(spg);
    SpgView view;
    ASSERT_TRUE(spg_parse(spg.data(), spg.size(), &view).ok());
    std::vector<uint32_t> storage(node_decoder_bytes(view.header) / 4);
    NodeDecoder decoder;
    ASSERT_EQ(decoder.init(view, storage.data(), storage.size() * 4), DecodeStatus::kOk);
    const Vec3 extent = ref.bbox_max - ref.bbox_min;
    const double mu = std::ldexp(1.0, kModelUnitBits) / std::max(extent.maxCoeff(), 1e-300);
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(decoder.extent_mu()[a], extent[a] * mu, 1.0);
    double worst_mean = 0, worst_axis = 0;
    for (uint32_t i = 0; i < view.header.node_count; ++i) {
      FixedNode n;
      ASSERT_EQ(decoder.decode(view.records + i * view.record_bytes, &n), DecodeStatus::kOk);
      const DecodedNode& r = ref.nodes[i];
      for (int a = 0; a < 3; ++a) {
        const double expect = (r.position.mean[a] - ref.bbox_min[a]) * mu;
        worst_mean = std::max(worst_mean, std::abs(n.mean[a] - expect));
        ASSERT_LE(std::abs(n.mean[a] - expect), 1.0) << "node " << i << " axis " << a;
      }
      for (int k = 0; k < 3; ++k) {
        const double sigma_mu = r.position.sigma[k] * mu;
        for (int c2 = 0; c2 < 3; ++c2) {
          const double expect = r.position.frame(c2, k) * sigma_mu;
          const double err = std::abs(n.axis[k][c2] - expect);
          worst_axis = std::max(worst_axis, err / std::max(sigma_mu, 1.0));
          // Q14 frame (<= 3 LSB) times sigma, plus sigma's own rounding.
          ASSERT_LE(err, sigma_mu * 4.0 / 16384 + 1.5) << "node " << i << " axis " << k;
        }
      }
      if (view.header.has_normals()) {
        for (int k = 0; k < 3; ++k)
          for (int c2 = 0; c2 < 3; ++c2)
            ASSERT_LE(std::abs(n.normal_frame[k][c2] - r.normal_frame(c2, k) * 16384), 4.5) << "node " << i;
        for (int k = 0; k < 2; ++k) ASSERT_LE(std::abs(n.sigma_n[k] - r.sigma_n[k] * 4096), 0.5) << "node " << i;
      }
      if (view.header.has_color()) {
        for (int c2 = 0; c2 < 3; ++c2) {
          ASSERT_EQ(n.color[c2], std::lround(r.color.mean[c2] * 255)) << "node " << i;
          for (int k = 0; k < 3; ++k) {
            const double expect = r.color.frame(c2, k) * r.color.sigma[k] * 4096;
            ASSERT_LE(std::abs(n.color_axis[k][c2] - expect), r.color.sigma[k] * 4096 * 4.0 / 16384 + 1.5);
          }
        }
      }
    }
    RecordProperty(std::string(c.name) + " worst_mean_mu", std::to_string(worst_mean));
    RecordProperty(std::string(c.name) + " worst_axis_rel", std::to_string(worst_axis));
  }
}

TEST(FixedTrig, FrameDecodeMatchesTheReferenceDecoder) {
  struct Layout {
    int theta, phi, psi;
    bool hemisphere;
  };
  for (const Layout l : {Layout{8, 10, 6, false}, Layout{4, 3, 3, true}}) {
    const AngleKind theta_kind = l.hemisphere ? AngleKind::kThetaHemisphere : AngleKind::kThetaSphere;
    std::vector<SinCosQ14> t(angle_table_entries(l.theta)), p(angle_table_entries(l.phi)), s(angle_table_entries(l.psi));
    ASSERT_TRUE(build_angle_table(theta_kind, l.theta, t.data(), t.size()));
    ASSERT_TRUE(build_angle_table(AngleKind::kPhi, l.phi, p.data(), p.size()));
    ASSERT_TRUE(build_angle_table(AngleKind::kPsi, l.psi, s.data(), s.size()));
    const FrameTables tables{t.data(), p.data(), s.data()};
    const AngleBits bits{l.theta, l.phi, l.psi, l.hemisphere};
    int worst = 0;
    for (uint32_t a = 0; a < t.size(); ++a)
      for (uint32_t b = 0; b < p.size(); b += (l.phi > 6 ? 7 : 1))
        for (uint32_t c = 0; c < s.size(); c += (l.psi > 4 ? 5 : 1)) {
          const FrameQ14 f = decode_frame_q14(tables, a, b, c);
          const Mat3 ref = decode_frame({static_cast<uint16_t>(a), static_cast<uint16_t>(b), static_cast<uint16_t>(c)}, bits);
          for (int axis = 0; axis < 3; ++axis)
            for (int k = 0; k < 3; ++k) {
              const int err = std::abs(f.axis[axis][k] - static_cast<int>(std::lround(ref(k, axis) * kQ14One)));
              worst = std::max(worst, err);
              // Measured worst: 3 LSB for 8-10-6 frames, 1 LSB for 4-3-3.
              ASSERT_LE(err, 4) << "theta " << a << " phi " << b << " psi " << c << " axis " << axis;
            }
        }
    RecordProperty(l.hemisphere ? "worst_lsb_colour" : "worst_lsb_position", worst);
  }
}

// The renderer's frames (raster/node_setup.h) never pass through
// decode_frame_q14: a camera-space frame is the per-frame table
// T(phi) = R Rz(phi) turned by two plane rotations, the normal frame's light
// and half terms come from Rz(phi)^T L, a colour frame is the same with
// R = I. Against the reference frame turned by the same integer camera (its
// Q14 rotation read as exact), every theta and a stride of phi and psi, for
// four cameras.
TEST(FrameAngles, CameraFramesAndLightTermsMatchTheReferenceDecoder) {
  PointCloud cloud = test::sphere_cloud(2000);
  for (const Vec3& p : cloud.positions) cloud.colors.push_back(((p + Vec3::Ones()) / 2).cwiseProduct(Vec3(1, 0.6, 0.3)));
  const std::vector<uint8_t> spg = test::encode(cloud);
  SpgView view;
  ASSERT_TRUE(spg_parse(spg.data(), spg.size(), &view).ok());
  std::vector<uint32_t> storage(node_decoder_bytes(view.header) / 4);
  NodeDecoder decoder;
  ASSERT_EQ(decoder.init(view, storage.data(), storage.size() * 4), DecodeStatus::kOk);
  const RecordLayout& l = view.header.layout;
  const AngleBits position_bits{l.width(Field::kFpTheta), l.width(Field::kFpPhi), l.width(Field::kFpPsi), false};
  const AngleBits color_bits{l.width(Field::kFcTheta), l.width(Field::kFcPhi), l.width(Field::kFcPsi), true};
  ASSERT_EQ(position_bits.phi, 10);
  std::vector<uint64_t> tables(frame_angles_bytes(kMaxAngleBits) / 8 + 1);
  FrameAngles angles;
  angles.init(tables.data(), kMaxAngleBits);
  const int16_t light[3] = {-5000, -9000, 12000}, half[3] = {2000, -16000, 3000};
  const Vec3 light_d(light[0], light[1], light[2]), half_d(half[0], half[1], half[2]);
  int worst_axis = 0, worst_light = 0, worst_color = 0;
  for (int view_index = 0; view_index < 4; ++view_index) {
    const Eigen::Matrix3d turn = (Eigen::AngleAxisd(0.7 + 1.9 * view_index, Vec3(0.3, 1, -0.2).normalized()) *
                                  Eigen::AngleAxisd(-0.4 * view_index, Vec3::UnitX()))
                                     .toRotationMatrix();
    Camera camera;
    Eigen::Matrix3d r;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        camera.rotation[i][j] = static_cast<int32_t>(std::lround(turn(i, j) * 16384));
        r(i, j) = camera.rotation[i][j] / 16384.0;
      }
    ASSERT_TRUE(angles.build(camera, decoder, light, half));
    const AngleBits& b = position_bits;
    for (uint32_t theta = 0; theta < (1u << b.theta); ++theta)
      for (uint32_t phi = view_index; phi < (1u << b.phi); phi += 5)
        for (uint32_t psi = theta % 3; psi < (1u << b.psi); psi += 3) {
          NodeFields f;
          f[Field::kFpTheta] = f[Field::kFnTheta] = static_cast<uint16_t>(theta);
          f[Field::kFpPhi] = f[Field::kFnPhi] = static_cast<uint16_t>(phi);
          f[Field::kFpPsi] = f[Field::kFnPsi] = static_cast<uint16_t>(psi);
          const FrameCode code{static_cast<uint16_t>(theta), static_cast<uint16_t>(phi), static_cast<uint16_t>(psi)};
          const Mat3 ref = decode_frame(code, b);  // columns: the axes in model space
          const Eigen::Matrix3d camera_ref = r * ref;
          int16_t axis[3][3];
          angles.position_frame(decoder.euler(FrameField::kPosition), f, axis);
          int32_t lt[3], ht[3];
          angles.light_terms(decoder.euler(FrameField::kNormal), f, lt, ht);
          for (int k = 0; k < 3; ++k) {
            for (int c = 0; c < 3; ++c) {
              const int err = std::abs(axis[k][c] - static_cast<int>(std::lround(camera_ref(c, k) * 16384)));
              worst_axis = std::max(worst_axis, err);
              ASSERT_LE(err, 4) << "theta " << theta << " phi " << phi << " psi " << psi << " axis " << k;
            }
            const int el = static_cast<int>(std::lround(std::abs(lt[k] - ref.col(k).dot(light_d))));
            const int eh = static_cast<int>(std::lround(std::abs(ht[k] - ref.col(k).dot(half_d))));
            worst_light = std::max({worst_light, el, eh});
            ASSERT_LE(std::max(el, eh), 4) << "theta " << theta << " phi " << phi << " psi " << psi << " axis " << k;
          }
        }
  }
  const AngleBits& c = color_bits;
  for (uint32_t theta = 0; theta < (1u << c.theta); ++theta)
    for (uint32_t phi = 0; phi < (1u << c.phi); ++phi)
      for (uint32_t psi = 0; psi < (1u << c.psi); ++psi) {
        NodeFields f;
        f[Field::kFcTheta] = static_cast<uint16_t>(theta);
        f[Field::kFcPhi] = static_cast<uint16_t>(phi);
        f[Field::kFcPsi] = static_cast<uint16_t>(psi);
        const Mat3 ref = decode_frame({static_cast<uint16_t>(theta), static_cast<uint16_t>(phi), static_cast<uint16_t>(psi)}, c);
        int16_t axis[3][3];
        FrameAngles::model_frame(decoder.euler(FrameField::kColor), f, Field::kFcTheta, axis);
        for (int k = 0; k < 3; ++k)
          for (int ch = 0; ch < 3; ++ch) {
            const int err = std::abs(axis[k][ch] - static_cast<int>(std::lround(ref(ch, k) * 16384)));
            worst_color = std::max(worst_color, err);
            ASSERT_LE(err, 2) << "theta " << theta << " phi " << phi << " psi " << psi;
          }
      }
  std::printf("worst Q14 LSB: camera-space axes %d, light and half terms %d, colour frames %d\n", worst_axis,
              worst_light, worst_color);
  RecordProperty("worst_lsb_camera_axes", worst_axis);
  RecordProperty("worst_lsb_light_terms", worst_light);
  RecordProperty("worst_lsb_colour_frames", worst_color);
}

}  // namespace
}  // namespace stipple
