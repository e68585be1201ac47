/*
 * png_check FILE WIDTH HEIGHT: exit 0 if FILE is a WIDTH x HEIGHT PNG
 * showing more than one colour, 1 otherwise.  The viewer's tests use it to
 * tell a real render from a blank or failed one.
 */
#include <stdio.h>
#include <stdlib.h>

#include <nerf.h>

int main(int argc, char **argv)
{
    if (argc != 4) {
        fprintf(stderr, "usage: png_check FILE WIDTH HEIGHT\n");
        return 2;
    }
    uint32_t w, h;
    float *px;
    int rc = nerf_image_read_png(argv[1], &w, &h, &px);
    if (rc != NERF_OK) {
        fprintf(stderr, "png_check: %s\n", nerf_last_error());
        return 1;
    }
    int status = 0;
    if (w != strtoul(argv[2], NULL, 10) || h != strtoul(argv[3], NULL, 10)) {
        fprintf(stderr, "png_check: %s is %ux%u, expected %sx%s\n", argv[1], w,
                h, argv[2], argv[3]);
        status = 1;
    }
    size_t n = (size_t)w * h, differ = 0;
    for (size_t k = 1; k < n; k++) {
        for (int c = 0; c < 3; c++) {
            if (px[4 * k + c] != px[c]) {
                differ++;
                break;
            }
        }
    }
    if (differ == 0) {
        fprintf(stderr, "png_check: %s is a single colour\n", argv[1]);
        status = 1;
    } else {
        printf("png_check: %s: %zu of %zu pixels differ from the first\n",
               argv[1], differ, n);
    }
    nerf_free(px);
    return status;
}
