// How a CHAI3D-style tool (a cGenericTool subclass) would drive innersphere's haptic loop:
// read the device, tick, send the force. Header-only. It compiles without CHAI3D: unless
// INNERSPHERE_WITH_CHAI3D is defined (and chai3d.h is on the include path), the few CHAI3D
// types it uses are stubbed below with the same member names.
#pragma once

#include "innersphere.h"

#include <cmath>

#ifdef INNERSPHERE_WITH_CHAI3D
#include "chai3d.h"
namespace innersphere_chai = chai3d;
#else
namespace innersphere_chai {  // stubs standing in for CHAI3D's types (not CHAI3D itself)
struct cVector3d {
    double x_ = 0, y_ = 0, z_ = 0;
    cVector3d() = default;
    cVector3d(double x, double y, double z) : x_(x), y_(y), z_(z) {}
    double x() const { return x_; }
    double y() const { return y_; }
    double z() const { return z_; }
};
struct cMatrix3d {
    double m[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    double getValue(int r, int c) const { return m[r][c]; }
};
struct cGenericHapticDevice {
    cVector3d pos;
    cMatrix3d rot;
    bool getPosition(cVector3d& p) { p = pos; return true; }
    bool getRotation(cMatrix3d& r) { r = rot; return true; }
    bool setForceAndTorqueAndGripperForce(const cVector3d&, const cVector3d&, double) { return true; }
};
}  // namespace innersphere_chai
#endif

namespace innersphere_example {

// The tool: owns an ist_haptic loop; call updateFromDevice() in CHAI3D's haptic thread
// (where cGenericTool::updateFromDevice / computeInteractionForces / applyToDevice run).
class InnerSphereTool {
  public:
    InnerSphereTool(innersphere_chai::cGenericHapticDevice* device, const ist_pair* pair,
                    const ist_haptic_params& params, double workspace_scale_mm_per_m)
        : device_(device), scale_(workspace_scale_mm_per_m), haptic_(ist_haptic_new(pair, &params)) {}
    ~InnerSphereTool() { ist_haptic_free(haptic_); }
    InnerSphereTool(const InnerSphereTool&) = delete;
    InnerSphereTool& operator=(const InnerSphereTool&) = delete;

    bool ok() const { return haptic_ != nullptr; }

    // One servo tick: device pose (m, CHAI3D's unit) → model (mm) → tick → force back.
    int updateFromDevice(double dt) {
        innersphere_chai::cVector3d p;
        innersphere_chai::cMatrix3d r;
        device_->getPosition(p);
        device_->getRotation(r);
        double m[16] = {r.getValue(0, 0), r.getValue(0, 1), r.getValue(0, 2), p.x() * scale_,
                        r.getValue(1, 0), r.getValue(1, 1), r.getValue(1, 2), p.y() * scale_,
                        r.getValue(2, 0), r.getValue(2, 1), r.getValue(2, 2), p.z() * scale_,
                        0, 0, 0, 1};  // row-major
        ist_pose pose;
        int s = ist_pose_from_matrix(m, 0, &pose);
        if (s != IST_OK) return s;
        s = ist_haptic_tick(haptic_, &pose, dt, &out_);
        if (s != IST_OK) return s;
        // N stays N; torque N*mm → N*m for CHAI3D.
        innersphere_chai::cVector3d f(out_.force[0], out_.force[1], out_.force[2]);
        innersphere_chai::cVector3d t(out_.torque[0] * 1e-3, out_.torque[1] * 1e-3, out_.torque[2] * 1e-3);
        device_->setForceAndTorqueAndGripperForce(f, t, 0.0);
        return IST_OK;
    }

    // The tool's pose to draw (mm, the model's frame).
    const ist_pose& toolPose() const { return out_.tool; }

  private:
    innersphere_chai::cGenericHapticDevice* device_;
    double scale_;
    ist_haptic* haptic_;
    ist_haptic_output out_{};
};

// Compiles (and runs once against the stubs) the adapter, so that the example's build
// checks it.
inline void compile_check_chai3d_adapter(const ist_pair* pair, ist_haptic_params params) {
#ifndef INNERSPHERE_WITH_CHAI3D
    innersphere_chai::cGenericHapticDevice device;
    device.pos = innersphere_chai::cVector3d(0.0, 0.0, -0.05);  // 50 mm away
    params.start.t[2] = -50.0;
    InnerSphereTool tool(&device, pair, params, 1000.0);
    if (tool.ok()) tool.updateFromDevice(0.001);
#else
    (void)pair;
    (void)params;
#endif
}

}  // namespace innersphere_example
