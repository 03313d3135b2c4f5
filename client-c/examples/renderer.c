/*
 * How a renderer in C connects: the loop of a renderer that draws nothing, line for line what
 * client-rs/examples/renderer.rs prints (numbers as Rust prints them), so that the two can be
 * compared on the same frames.
 *
 * The scene's geometry arrives on connecting and after every load or reset: a line per part's
 * mesh. Each wake-up "draws" the newest state, frames that arrived meanwhile are skipped: a line
 * per part of a new parts frame, and for every hand (right, then left) of a new hand frame a
 * line for the hand and one per segment, naming the hand's user (the scene info names the users).
 *
 *     cc -Wall -Wextra -I client-c/include client-c/examples/renderer.c \
 *        -L target/release -lvas_client -Wl,-rpath,target/release -o renderer
 *     ./renderer --prefix demo --frames 20
 */

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "vas_client.h"

/* A number as Rust's `{:?}` prints it: the fewest digits that read back as the same value
 * (17 significant digits at most, 9 for a float), in positional notation with at least one decimal, or in
 * exponential notation below 1e-4 and from 1e16 on. `is_single` reads back as a float. */
static void print_number(double value, int is_single) {
    if (isnan(value)) {
        fputs("NaN", stdout);
        return;
    }
    if (signbit(value)) {
        putchar('-');
        value = -value;
    }
    if (isinf(value)) {
        fputs("inf", stdout);
        return;
    }
    if (value == 0.0) {
        fputs("0.0", stdout);
        return;
    }
    /* The shortest of "d.ddde±x" that reads back exactly. */
    char text[40];
    int most = is_single ? 9 : 17;
    for (int count = 1; count <= most; count++) {
        snprintf(text, sizeof text, "%.*e", count - 1, value);
        if (is_single ? strtof(text, NULL) == (float)value : strtod(text, NULL) == value) {
            break;
        }
    }
    char digits[24];
    size_t digit_count = 0;
    const char *at = text;
    for (; *at != 'e'; at++) {
        if (*at != '.') {
            digits[digit_count++] = *at;
        }
    }
    int exponent = atoi(at + 1);
    while (digit_count > 1 && digits[digit_count - 1] == '0') {
        digit_count--;
    }
    int exponential = is_single ? (float)value < 1e-4f || (float)value >= 1e16f
                                : value < 1e-4 || value >= 1e16;
    if (exponential) {
        printf("%c", digits[0]);
        if (digit_count > 1) {
            printf(".%.*s", (int)(digit_count - 1), digits + 1);
        }
        printf("e%d", exponent);
    } else if (exponent < 0) {
        fputs("0.", stdout);
        for (int zero = 0; zero < -exponent - 1; zero++) {
            putchar('0');
        }
        printf("%.*s", (int)digit_count, digits);
    } else {
        size_t whole = (size_t)exponent + 1;
        for (size_t i = 0; i < whole; i++) {
            putchar(i < digit_count ? digits[i] : '0');
        }
        if (digit_count > whole) {
            printf(".%.*s", (int)(digit_count - whole), digits + whole);
        } else {
            fputs(".0", stdout);
        }
    }
}

/* `[a, b, c]` as Rust prints an array of numbers. */
static void print_numbers(const double *values, size_t count, int is_single) {
    putchar('[');
    for (size_t i = 0; i < count; i++) {
        if (i > 0) {
            fputs(", ", stdout);
        }
        print_number(values[i], is_single);
    }
    putchar(']');
}

/* A string in quotes, escaped as Rust's `{:?}` escapes it. */
static void print_quoted(const char *text) {
    putchar('"');
    for (const unsigned char *at = (const unsigned char *)text; *at != '\0'; at++) {
        switch (*at) {
        case '"': fputs("\\\"", stdout); break;
        case '\\': fputs("\\\\", stdout); break;
        case '\n': fputs("\\n", stdout); break;
        case '\r': fputs("\\r", stdout); break;
        case '\t': fputs("\\t", stdout); break;
        default:
            if (*at < 0x20 || *at == 0x7f) {
                printf("\\u{%x}", *at);
            } else {
                putchar(*at);
            }
        }
    }
    putchar('"');
}

/* Where a real renderer uploads the scene's meshes: a line per part's mesh. */
static void upload_meshes(const VasGeometry *geometry) {
    for (size_t id = 0; id < geometry->part_count; id++) {
        const VasMesh *mesh = &geometry->parts[id];
        double min[3] = {0.0, 0.0, 0.0}, max[3] = {0.0, 0.0, 0.0};
        for (size_t v = 0; v < mesh->vertex_count; v++) {
            for (int axis = 0; axis < 3; axis++) {
                double value = mesh->positions[v][axis];
                if (v == 0 || value < min[axis]) min[axis] = value;
                if (v == 0 || value > max[axis]) max[axis] = value;
            }
        }
        printf("mesh part=%zu name=", id);
        print_quoted(mesh->name);
        printf(" triangles=%zu min=", mesh->triangle_count);
        print_numbers(min, 3, 1);
        fputs(" max=", stdout);
        print_numbers(max, 3, 1);
        putchar('\n');
    }
}

/* Each part's mesh goes to its pose: a line per part. */
static void draw_parts(const VasGeometry *geometry, const VasPartsFrameHeader *header,
                       const VasPartState *parts, size_t count) {
    for (size_t i = 0; i < count; i++) {
        const VasPartState *part = &parts[i];
        const char *name = part->id < geometry->part_count ? geometry->parts[part->id].name : "?";
        printf("part frame=%llu id=%u name=", (unsigned long long)header->frame, part->id);
        print_quoted(name);
        fputs(" position=", stdout);
        print_numbers(part->position, 3, 0);
        fputs(" rotation=", stdout);
        print_numbers(part->rotation, 4, 0);
        putchar('\n');
    }
}

/* Each segment's mesh of the hand goes where the server verified the segment, no kinematics
 * here: a line for the hand, then one per segment, each naming the hand's user and side. */
static void draw_hand(const VasSceneInfo *scene, const VasHandFrame *hand) {
    const char *user = hand->user < scene->user_count ? scene->users[hand->user] : "?";
    const char *side = vas_hand_side_name(hand->hand);
    const char *grasp = vas_grasp_type_name(hand->grasp_type);
    side = side != NULL ? side : "unknown";
    unsigned long long frame = (unsigned long long)hand->frame;
    printf("hand frame=%llu user=", frame);
    print_quoted(user);
    printf(" side=%s grasp=%s position=", side, grasp != NULL ? grasp : "unknown");
    print_numbers(hand->root.position, 3, 0);
    putchar('\n');
    for (uint32_t s = 0; s < hand->segment_count && s < VAS_HAND_SEGMENT_COUNT; s++) {
        printf("segment frame=%llu user=", frame);
        print_quoted(user);
        printf(" side=%s name=%s position=", side, vas_hand_segment_name(s));
        print_numbers(hand->segments[s].position, 3, 0);
        fputs(" rotation=", stdout);
        print_numbers(hand->segments[s].rotation, 4, 0);
        putchar('\n');
    }
}

/* Prints the library's last error and says so. */
static int failed(const char *what) {
    fprintf(stderr, "renderer: %s: %s\n", what, vas_last_error_message());
    return 1;
}

/* The loop; returns the exit code. */
static int render(VasClient *client, long long frames) {
    /* What was drawn last: a renderer redraws when the newest state differs, whichever poll
     * brought it (the meshes may come after the first frames, or before). */
    long long drawn = 0;
    const VasSceneInfo *scene = NULL; /* The users' names, asked for with each scene's meshes. */
    int have_generation = 0, have_parts = 0, have_hands = 0;
    uint64_t generation = 0, parts_frame = 0, hand_frame = 0;
    while (frames < 0 || drawn < frames) {
        VasWake wake;
        if (vas_client_wait(client, 1000, &wake) != VAS_STATUS_OK) return failed("wait");
        if (wake == VAS_WAKE_TIMEOUT) continue;
        if (wake == VAS_WAKE_TERMINATED) break;
        if (vas_client_poll(client, NULL) != VAS_STATUS_OK) return failed("poll");
        const VasGeometry *geometry = NULL;
        VasStatus status = vas_client_geometry(client, &geometry);
        if (status < 0) return failed("geometry");
        if (status == VAS_STATUS_EMPTY) continue; /* Nothing to draw before the meshes. */
        if (!have_generation || generation != geometry->generation) {
            have_generation = 1;
            generation = geometry->generation;
            upload_meshes(geometry); /* Once per scene, */
            /* with the names of its users. */
            if (vas_client_scene_info(client, 5000, &scene) != VAS_STATUS_OK) {
                return failed("scene info");
            }
        }
        VasPartsFrameHeader header;
        const VasPartState *parts = NULL;
        size_t part_count = 0;
        status = vas_client_latest_parts(client, &header, &parts, &part_count);
        if (status < 0) return failed("parts");
        int new_parts = status == VAS_STATUS_OK && (!have_parts || header.frame != parts_frame);
        /* Every hand, right then left, published each frame under one number: a frame's hands
         * are drawn together (a poll may end between two of them). */
        const VasHandFrame *hands = NULL;
        size_t hand_count = 0;
        if (vas_client_latest_hands(client, &hands, &hand_count) != VAS_STATUS_OK) {
            return failed("hands");
        }
        int new_hands = hand_count > 0 && (!have_hands || hands[0].frame != hand_frame);
        for (size_t h = 1; h < hand_count; h++) {
            new_hands = new_hands && hands[h].frame == hands[0].frame;
        }
        if (!new_parts && !new_hands) continue; /* Events or force frames alone draw nothing. */
        drawn++;
        if (new_parts) {
            have_parts = 1;
            parts_frame = header.frame;
            draw_parts(geometry, &header, parts, part_count);
        }
        if (new_hands) {
            have_hands = 1;
            hand_frame = hands[0].frame;
            for (size_t h = 0; h < hand_count; h++) draw_hand(scene, &hands[h]);
        }
        fflush(stdout);
    }
    return 0;
}

int main(int argc, char **argv) {
    const char *prefix = NULL;
    long long frames = -1; /* Until SIGINT or SIGTERM. */
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--prefix") == 0 && i + 1 < argc) {
            prefix = argv[++i];
        } else if (strcmp(argv[i], "--frames") == 0 && i + 1 < argc) {
            frames = atoll(argv[++i]);
        } else {
            fprintf(stderr, "usage: %s [--prefix P] [--frames N]\n", argv[0]);
            return 2;
        }
    }
    /* With the signals handled, Ctrl-C ends the loop and the client leaves cleanly. A renderer
     * only reads: it takes the render role, and no input ports. */
    VasClient *client = NULL;
    if (vas_client_connect(prefix, VAS_ROLE_RENDER, true, &client) != VAS_STATUS_OK) {
        return failed("connect");
    }
    int code = render(client, frames);
    vas_client_free(client);
    return code;
}
