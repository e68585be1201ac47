// nerf_orbit: libnerf from C++.  Writes the built-in scene to a scratch
// folder, trains the tiny preset on it for a few steps and renders one view
// of the orbit around it to a PNG.
//
//   nerf_orbit OUT.png [STEPS [AZIMUTH_DEGREES]]
//
// The C API stays as it is; the few lines in namespace nerfxx give its
// handles owners (std::unique_ptr with the matching *_destroy) and turn
// failing statuses into exceptions that carry nerf_last_error().

#include <nerf.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace nerfxx {

// A failed libnerf call: the status and the library's message.
class error : public std::runtime_error {
  public:
    error(int status, const std::string &call)
        : std::runtime_error(call + ": " + nerf_status_string(status) + ": " +
                             nerf_last_error()),
          status_(status)
    {
    }
    int status() const noexcept
    {
        return status_;
    }

  private:
    int status_;
};

// Read nerf_last_error() right away: it is per thread and the next failing
// call replaces it.
inline void check(int status, const char *call)
{
    if (status != NERF_OK) {
        throw error(status, call);
    }
}

template <typename T, void (*Destroy)(T *)> struct destroyer {
    void operator()(T *p) const noexcept
    {
        Destroy(p);
    }
};

using model =
    std::unique_ptr<nerf_model, destroyer<nerf_model, nerf_model_destroy>>;
using sampler = std::unique_ptr<nerf_sampler,
                                destroyer<nerf_sampler, nerf_sampler_destroy>>;
using renderer =
    std::unique_ptr<nerf_renderer,
                    destroyer<nerf_renderer, nerf_renderer_destroy>>;
using dataset = std::unique_ptr<nerf_dataset,
                                destroyer<nerf_dataset, nerf_dataset_destroy>>;
using trainer = std::unique_ptr<nerf_trainer,
                                destroyer<nerf_trainer, nerf_trainer_destroy>>;

inline model create_model(const nerf_model_options &opts)
{
    nerf_model *m = nullptr;
    check(nerf_model_create(&m, &opts), "nerf_model_create");
    return model(m);
}

inline sampler create_sampler(const nerf_sampler_options &opts)
{
    nerf_sampler *s = nullptr;
    check(nerf_sampler_create(&s, &opts), "nerf_sampler_create");
    return sampler(s);
}

inline dataset load_dataset(const std::string &dir,
                            const nerf_dataset_options &opts)
{
    nerf_dataset *d = nullptr;
    check(nerf_dataset_load(&d, dir.c_str(), &opts), "nerf_dataset_load");
    return dataset(d);
}

// The trainer and the renderer only borrow what they are given: keep the
// model, sampler and dataset alive longer (declare them first).
inline trainer create_trainer(const model &m, const dataset &d,
                              const sampler &s,
                              const nerf_trainer_options &opts)
{
    nerf_trainer *t = nullptr;
    check(nerf_trainer_create(&t, m.get(), d.get(), s.get(), &opts),
          "nerf_trainer_create");
    return trainer(t);
}

inline renderer create_renderer(const model &m, const sampler &s,
                                const nerf_renderer_options &opts)
{
    nerf_renderer *r = nullptr;
    check(nerf_renderer_create(&r, m.get(), s.get(), &opts),
          "nerf_renderer_create");
    return renderer(r);
}

// A folder under the system's temporary directory, removed with its
// contents when the object goes out of scope.
class scratch_dir {
  public:
    scratch_dir()
    {
        auto pattern =
            (std::filesystem::temp_directory_path() / "nerf_orbit.XXXXXX")
                .string();
        std::vector<char> buf(pattern.begin(), pattern.end());
        buf.push_back('\0');
        if (mkdtemp(buf.data()) == nullptr) {
            throw std::runtime_error("cannot create a folder like " + pattern);
        }
        path_ = buf.data();
    }
    ~scratch_dir()
    {
        std::error_code ignored;
        std::filesystem::remove_all(path_, ignored);
    }
    scratch_dir(const scratch_dir &) = delete;
    scratch_dir &operator=(const scratch_dir &) = delete;
    const std::filesystem::path &path() const noexcept
    {
        return path_;
    }

  private:
    std::filesystem::path path_;
};

} // namespace nerfxx

namespace {

// Progress callbacks are called from C: an exception must never leave one.
int report(const nerf_progress *p, void *) noexcept
{
    if (p->done % 10 == 0 || p->done == p->total) {
        std::printf("step %llu/%llu  loss %.4f  psnr %.2f dB\n",
                    static_cast<unsigned long long>(p->done),
                    static_cast<unsigned long long>(p->total), p->loss,
                    p->psnr);
    }
    return 0;
}

// The view from azimuth az_deg at 30 degrees elevation, radius 4, looking
// at the origin with z up: where the built-in scene's cameras sit.
nerf_camera orbit_camera(double az_deg, uint32_t width, uint32_t height,
                         float focal)
{
    const double pi = 3.14159265358979323846;
    const double az = az_deg * pi / 180.0, elev = 30.0 * pi / 180.0;
    nerf_camera cam;
    nerfxx::check(NERF_CAMERA_INIT(&cam), "nerf_camera_init");
    cam.width = width;
    cam.height = height;
    cam.fx = cam.fy = focal;
    cam.cx = 0.5f * static_cast<float>(width);
    cam.cy = 0.5f * static_cast<float>(height);
    const float eye[3] = {
        static_cast<float>(4.0 * std::cos(elev) * std::cos(az)),
        static_cast<float>(4.0 * std::cos(elev) * std::sin(az)),
        static_cast<float>(4.0 * std::sin(elev))};
    const float target[3] = {0, 0, 0}, up[3] = {0, 0, 1};
    nerfxx::check(nerf_camera_look_at(&cam, eye, target, up),
                  "nerf_camera_look_at");
    return cam;
}

void run(const std::string &out, uint64_t steps, double azimuth)
{
    nerfxx::scratch_dir scratch;
    const std::string scene = (scratch.path() / "scene").string();

    nerf_scene_options so;
    nerfxx::check(NERF_SCENE_OPTIONS_INIT(&so), "nerf_scene_options_init");
    so.width = so.height = 48;
    so.n_train = 40;
    so.n_val = 0;
    so.n_test = 1;
    nerfxx::check(nerf_scene_write(scene.c_str(), &so), "nerf_scene_write");

    nerf_dataset_options dopt;
    nerfxx::check(NERF_DATASET_OPTIONS_INIT(&dopt),
                  "nerf_dataset_options_init");
    const nerfxx::dataset train = nerfxx::load_dataset(scene, dopt);

    nerf_model_options mo;
    nerfxx::check(NERF_MODEL_OPTIONS_INIT(&mo), "nerf_model_options_init");
    nerfxx::check(nerf_model_options_preset(&mo, NERF_PRESET_TINY),
                  "nerf_model_options_preset");
    const nerfxx::model model = nerfxx::create_model(mo);
    // The small network learns faster with a higher rate than the paper's.
    nerfxx::check(
        nerf_model_set_param(model.get(), NERF_PARAM_LEARNING_RATE, 5e-3),
        "nerf_model_set_param");

    nerf_sampler_options sopt;
    nerfxx::check(NERF_SAMPLER_OPTIONS_INIT(&sopt),
                  "nerf_sampler_options_init");
    nerfxx::check(nerf_sampler_options_preset(&sopt, NERF_PRESET_TINY),
                  "nerf_sampler_options_preset");
    nerfxx::check(nerf_dataset_bounds(train.get(), &sopt.t_near, &sopt.t_far),
                  "nerf_dataset_bounds");
    const nerfxx::sampler sampler = nerfxx::create_sampler(sopt);

    nerf_trainer_options topt;
    nerfxx::check(NERF_TRAINER_OPTIONS_INIT(&topt),
                  "nerf_trainer_options_init");
    topt.batch_rays = 256;
    {
        const nerfxx::trainer trainer =
            nerfxx::create_trainer(model, train, sampler, topt);
        nerfxx::check(nerf_trainer_set_progress(trainer.get(), report, nullptr),
                      "nerf_trainer_set_progress");
        nerfxx::check(nerf_trainer_run(trainer.get(), steps, nullptr),
                      "nerf_trainer_run");
    } // The trainer is released here; the model keeps what it learnt.

    nerf_renderer_options ropt;
    nerfxx::check(NERF_RENDERER_OPTIONS_INIT(&ropt),
                  "nerf_renderer_options_init");
    ropt.white_background = 1; // as the scene's images were composited
    const nerfxx::renderer renderer =
        nerfxx::create_renderer(model, sampler, ropt);

    nerf_camera cam0;
    nerfxx::check(NERF_CAMERA_INIT(&cam0), "nerf_camera_init");
    nerfxx::check(nerf_dataset_camera(train.get(), 0, &cam0),
                  "nerf_dataset_camera");
    const uint32_t size = 64;
    // The training cameras' field of view, at the size of this image.
    const float focal =
        cam0.fx * static_cast<float>(size) / static_cast<float>(cam0.width);
    const nerf_camera cam = orbit_camera(azimuth, size, size, focal);
    std::vector<uint8_t> rgb(static_cast<size_t>(size) * size * 3);
    nerfxx::check(nerf_renderer_render_image_u8(renderer.get(), &cam,
                                                rgb.data(), nullptr, nullptr,
                                                size * size),
                  "nerf_renderer_render_image_u8");
    nerfxx::check(nerf_image_write_png8(out.c_str(), size, size, 3, rgb.data()),
                  "nerf_image_write_png8");
    std::printf("wrote %s (%ux%u, model at step %llu)\n", out.c_str(), size,
                size,
                static_cast<unsigned long long>(nerf_model_step(model.get())));
}

} // namespace

int main(int argc, char **argv)
{
    if (argc < 2 || argc > 4) {
        std::fprintf(stderr,
                     "usage: nerf_orbit OUT.png [STEPS [AZIMUTH_DEGREES]]\n");
        return 2;
    }
    const uint64_t steps = argc > 2 ? std::strtoull(argv[2], nullptr, 10) : 100;
    const double azimuth = argc > 3 ? std::strtod(argv[3], nullptr) : 45.0;
    try {
        run(argv[1], steps > 0 ? steps : 1, azimuth);
    } catch (const nerfxx::error &e) {
        std::fprintf(stderr, "nerf_orbit: libnerf error %d: %s\n", e.status(),
                     e.what());
        return 1;
    } catch (const std::exception &e) {
        std::fprintf(stderr, "nerf_orbit: %s\n", e.what());
        return 1;
    }
    return 0;
}
